// socketcan_bus.cpp — see socketcan_bus.hpp.
#include "hal/socketcan/socketcan_bus.hpp"

#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <linux/sock_diag.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

namespace scopekin::hal {

namespace {

std::string system_reason(const char* what) {
    return std::string{what} + ": " + std::strerror(errno);
}

std::uint64_t clock_us(clockid_t clock) {
    timespec now{};
    clock_gettime(clock, &now);
    return static_cast<std::uint64_t>(now.tv_sec) * 1000000U +
           static_cast<std::uint64_t>(now.tv_nsec) / 1000U;
}

/// CLOCK_REALTIME and CLOCK_MONOTONIC at (nearly) one instant: the realtime reading between two
/// monotonic ones, moved to the second; of up to 3 tries the tightest (a thread preempted
/// between the readings would otherwise shift the offset by the preemption).
void read_clocks(std::uint64_t& realtime_us, std::uint64_t& monotonic_us) {
    std::uint64_t best_width = ~std::uint64_t{0};
    for (int attempt = 0; attempt < 3; ++attempt) {  // bound: 3
        const std::uint64_t before = clock_us(CLOCK_MONOTONIC);
        const std::uint64_t realtime = clock_us(CLOCK_REALTIME);
        const std::uint64_t after = clock_us(CLOCK_MONOTONIC);
        const std::uint64_t width = after - before;
        if (width < best_width) {
            best_width = width;
            realtime_us = realtime + width / 2U;
            monotonic_us = after;
        }
        if (width <= 20U) {
            break;
        }
    }
}

/// Waits until the socket is ready for `events` or `timeout_us` passes.
bool wait_ready(int socket, short events, std::uint32_t timeout_us) {
    pollfd descriptor{socket, events, 0};
    const int timeout_ms = static_cast<int>((timeout_us + 999U) / 1000U);
    for (;;) {
        const int ready = ::poll(&descriptor, 1, timeout_ms);
        if (ready < 0 && errno == EINTR) {
            return false;  // a signal: let the caller's loop look at its stop flag
        }
        return ready > 0;
    }
}

can_frame to_kernel(const CanFrame& frame) {
    can_frame kernel{};
    if (frame.error) {
        kernel.can_id = (frame.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
    } else if (frame.extended) {
        kernel.can_id = (frame.id & CAN_EFF_MASK) | CAN_EFF_FLAG;
    } else {
        kernel.can_id = frame.id & CAN_SFF_MASK;
    }
    if (frame.remote) {
        kernel.can_id |= CAN_RTR_FLAG;
    }
    kernel.len = frame.length;
    std::memcpy(kernel.data, frame.data.data(), frame.length);
    return kernel;
}

/// The kernel's form of a filter: the id format and "no remote frame" are part of the match.
can_filter to_kernel_filter(const CanIdFilter& filter) {
    const canid_t width = filter.extended ? CAN_EFF_MASK : CAN_SFF_MASK;
    return can_filter{(filter.id & width) | (filter.extended ? CAN_EFF_FLAG : 0U),
                      (filter.mask & width) | CAN_EFF_FLAG | CAN_RTR_FLAG};
}

/// Sets CAN_RAW_FILTER; no filter = the kernel's default, one filter that passes every frame.
bool set_kernel_filters(int socket, std::span<const CanIdFilter> filters) {
    std::array<can_filter, kCanMaxReceiveFilters> kernel{};
    std::size_t count = 0;
    for (const CanIdFilter& filter : filters) {  // bound: kCanMaxReceiveFilters (checked)
        kernel[count] = to_kernel_filter(filter);
        ++count;
    }
    if (count == 0U) {
        kernel[0] = can_filter{0U, 0U};
        count = 1;
    }
    return setsockopt(socket, SOL_CAN_RAW, CAN_RAW_FILTER, kernel.data(),
                      static_cast<socklen_t>(count * sizeof(can_filter))) == 0;
}

CanFrame from_kernel(const can_frame& kernel) {
    CanFrame frame{};
    frame.error = (kernel.can_id & CAN_ERR_FLAG) != 0U;
    frame.extended = !frame.error && (kernel.can_id & CAN_EFF_FLAG) != 0U;
    frame.remote = !frame.error && (kernel.can_id & CAN_RTR_FLAG) != 0U;
    if (frame.error) {
        frame.id = kernel.can_id & CAN_ERR_MASK;
    } else {
        frame.id = kernel.can_id & (frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    }
    frame.length = kernel.len > CAN_MAX_DLEN ? std::uint8_t{CAN_MAX_DLEN} : kernel.len;
    std::memcpy(frame.data.data(), kernel.data, frame.length);
    return frame;
}

/// The kernel's count of frames this socket dropped for a full receive buffer (sk_drops, the
/// count SO_RXQ_OVFL also carries), read now; false if the kernel does not say.
bool read_kernel_drops(int fd, std::uint32_t& dropped) {
    std::array<std::uint32_t, SK_MEMINFO_VARS> meminfo{};
    socklen_t length = sizeof(meminfo);
    if (getsockopt(fd, SOL_SOCKET, SO_MEMINFO, meminfo.data(), &length) != 0 ||
        length <= static_cast<socklen_t>(SK_MEMINFO_DROPS * sizeof(std::uint32_t))) {
        return false;
    }
    dropped = meminfo[SK_MEMINFO_DROPS];
    return true;
}

}  // namespace

SocketCanBus::~SocketCanBus() {
    close();
}

void SocketCanBus::close() {
    if (socket_ >= 0) {
        ::close(socket_);
        socket_ = -1;
    }
}

bool SocketCanBus::open(const SocketCanConfig& config, std::string& error) {
    close();
    counters_ = {};
    receive_clock_ = RealtimeToMonotonic{};
    const std::string where = "CAN interface '" + config.interface + "'";
    if (config.interface.empty() || config.interface.size() >= IFNAMSIZ) {
        error = where + ": the name must have 1 to " + std::to_string(IFNAMSIZ - 1) + " characters";
        return false;
    }
    const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        error = where + ": " + system_reason("socket(PF_CAN, SOCK_RAW, CAN_RAW)") +
                (errno == EAFNOSUPPORT ? " (this kernel has no CAN support: load the can and "
                                         "can-raw modules)"
                                       : "");
        return false;
    }
    socket_ = fd;
    const unsigned int index = if_nametoindex(config.interface.c_str());
    if (index == 0U) {
        error = where + ": " + system_reason("no such interface (if_nametoindex)");
        close();
        return false;
    }
    if (config.receive_ids.size() > kCanMaxReceiveFilters) {
        error =
            where + ": at most " + std::to_string(kCanMaxReceiveFilters) + " receive identifiers";
        close();
        return false;
    }
    std::array<CanIdFilter, kCanMaxReceiveFilters> filters{};
    std::size_t count = 0;
    for (const std::uint32_t id : config.receive_ids) {  // bound: kCanMaxReceiveFilters
        filters[count] = CanIdFilter{id & CAN_SFF_MASK, kCanStandardIdMask, false};
        ++count;
    }
    if (count > 0U &&
        !set_kernel_filters(fd, std::span<const CanIdFilter>{filters.data(), count})) {
        error = where + ": " + system_reason("setsockopt(CAN_RAW_FILTER)");
        close();
        return false;
    }
    const can_err_mask_t error_mask = config.receive_error_frames ? CAN_ERR_MASK : 0U;
    const int on = 1;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &error_mask, sizeof(error_mask)) != 0 ||
        setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof(on)) != 0 ||
        setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on)) != 0) {
        error =
            where + ": " + system_reason("setsockopt(error filter / SO_TIMESTAMP / SO_RXQ_OVFL)");
        close();
        return false;
    }
    if (config.receive_buffer_bytes > 0 &&
        setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &config.receive_buffer_bytes,
                   sizeof(config.receive_buffer_bytes)) != 0) {
        error = where + ": " + system_reason("setsockopt(SO_RCVBUF)");
        close();
        return false;
    }
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = static_cast<int>(index);
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
        error = where + ": " + system_reason("bind");
        close();
        return false;
    }
    return true;
}

CanStatus SocketCanBus::set_receive_filter(std::span<const CanIdFilter> filters) {
    if (filters.size() > kCanMaxReceiveFilters) {
        return CanStatus::invalid;
    }
    if (socket_ < 0 || !set_kernel_filters(socket_, filters)) {
        ++counters_.backend_errors;
        return CanStatus::failed;
    }
    return CanStatus::ok;
}

CanStatus SocketCanBus::send(const CanFrame& frame, std::uint32_t timeout_us) {
    if (!is_valid_can_frame(frame) || frame.error || socket_ < 0) {
        ++counters_.send_failures;
        return CanStatus::invalid;
    }
    const can_frame kernel = to_kernel(frame);
    for (int attempt = 0; attempt < 2; ++attempt) {  // bound: one retry after waiting for room
        const ssize_t written = ::write(socket_, &kernel, sizeof(kernel));
        if (written == static_cast<ssize_t>(sizeof(kernel))) {
            ++counters_.sent;
            return CanStatus::ok;
        }
        if (written < 0 && (errno == ENETDOWN || errno == ENODEV)) {
            ++counters_.send_failures;
            return CanStatus::bus_off;
        }
        const bool queue_full =
            written < 0 && (errno == EAGAIN || errno == ENOBUFS || errno == EINTR);
        if (!queue_full) {
            ++counters_.send_failures;
            ++counters_.backend_errors;
            return CanStatus::failed;
        }
        if (attempt == 0 && (timeout_us == 0U || !wait_ready(socket_, POLLOUT, timeout_us))) {
            break;
        }
    }
    ++counters_.send_failures;
    return CanStatus::timeout;
}

CanStatus SocketCanBus::receive(ReceivedCanFrame& received, std::uint32_t timeout_us) {
    if (socket_ < 0) {
        return CanStatus::failed;
    }
    // The drop count is refreshed at every receive, not only from the next frame's SO_RXQ_OVFL
    // (which arrives behind every frame queued before the drop): the executive, which reads
    // counters() after its receive loop, sees a drop in the period it happened.
    std::uint32_t kernel_drops = 0;
    if (read_kernel_drops(socket_, kernel_drops)) {
        counters_.dropped = kernel_drops;
    }
    for (int attempt = 0; attempt < 2; ++attempt) {  // bound: one wait, then one more read
        can_frame kernel{};
        iovec vector{&kernel, sizeof(kernel)};
        alignas(cmsghdr) char
            control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t))]{};
        msghdr message{};
        message.msg_iov = &vector;
        message.msg_iovlen = 1;
        message.msg_control = control;
        message.msg_controllen = sizeof(control);
        const ssize_t length = ::recvmsg(socket_, &message, 0);
        if (length == static_cast<ssize_t>(sizeof(kernel))) {
            std::uint64_t realtime_now = 0;
            std::uint64_t monotonic_now = 0;
            read_clocks(realtime_now, monotonic_now);
            std::uint64_t stamp_realtime = realtime_now;
            for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
                if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
                    timeval stamp{};
                    std::memcpy(&stamp, CMSG_DATA(c), sizeof(stamp));
                    stamp_realtime = static_cast<std::uint64_t>(stamp.tv_sec) * 1000000U +
                                     static_cast<std::uint64_t>(stamp.tv_usec);
                } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
                    std::uint32_t dropped = 0;
                    std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
                    counters_.dropped = dropped;  // the kernel's running total for this socket
                }
            }
            received.frame = from_kernel(kernel);
            received.timestamp_us = receive_clock_.map(stamp_realtime, realtime_now, monotonic_now);
            count_received_frame(counters_, received.frame);
            return CanStatus::ok;
        }
        if (length >= 0 || (errno != EAGAIN && errno != EINTR)) {
            ++counters_.backend_errors;  // a short read cannot happen on CAN_RAW; count it anyway
            return CanStatus::failed;
        }
        if (attempt == 0 && (timeout_us == 0U || !wait_ready(socket_, POLLIN, timeout_us))) {
            break;
        }
    }
    return CanStatus::timeout;
}

}  // namespace scopekin::hal
