// can_bus.hpp — the CAN bus as the firmware sees it: classic frames (0..8 bytes), 11- or 29-bit
// identifiers, send with a timeout, receive with a timestamp, receive filters, counters.
//
// Backends: hal/socketcan (Linux CAN_RAW), hal/loopback (in memory, simulated time),
// on bare metal too (mps2-an386 has no CAN controller, so the loopback wire stands in for one).
// The firmware's cyclic executive holds a
// CanBus& and never knows which one it has; `main` chooses.
//
// Timeouts are in microseconds; 0 means "poll: do not wait".
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace scopekin::hal {

inline constexpr std::uint32_t kCanStandardIdMask = 0x7FFU;       ///< 11 bits
inline constexpr std::uint32_t kCanExtendedIdMask = 0x1FFFFFFFU;  ///< 29 bits
inline constexpr std::uint8_t kCanMaxLength = 8;                  ///< classic CAN

/// Error-frame classes (the bits of CanFrame::id when CanFrame::error is set).  Same values as
/// Linux's <linux/can/error.h> CAN_ERR_*, so the SocketCAN backend passes them through unchanged
/// and a candump log's error frames read the same everywhere.
enum CanErrorClass : std::uint32_t {
    kCanErrorTxTimeout = 0x001U,
    kCanErrorLostArbitration = 0x002U,
    kCanErrorController = 0x004U,  ///< data[1] holds the controller state (warning/passive)
    kCanErrorProtocol = 0x008U,
    kCanErrorTransceiver = 0x010U,
    kCanErrorNoAck = 0x020U,
    kCanErrorBusOff = 0x040U,
    kCanErrorBusError = 0x080U,
    kCanErrorRestarted = 0x100U,  ///< the controller left bus-off
};

struct CanFrame {
    std::uint32_t id{0};     ///< identifier (11 or 29 bits), or error classes if `error`
    bool extended{false};    ///< 29-bit identifier
    bool remote{false};      ///< remote transmission request (no data)
    bool error{false};       ///< error frame reported by the controller / driver
    std::uint8_t length{0};  ///< data length 0..8
    std::array<std::uint8_t, kCanMaxLength> data{};
};

/// A received frame with the time it arrived (the backend's clock: kernel receive timestamp on
/// SocketCAN, simulated time on loopback), in microseconds.
struct ReceivedCanFrame {
    CanFrame frame{};
    std::uint64_t timestamp_us{0};
};

enum class CanStatus : std::uint8_t {
    ok,
    timeout,  ///< nothing received / could not send within the timeout
    bus_off,  ///< the controller is bus-off (or the interface is down): frame not sent
    invalid,  ///< the frame itself is invalid (length > 8, id out of range): not sent
    failed,   ///< any other backend error (counted in CanCounters::backend_errors)
};

/// Counters since the bus was opened (they wrap at 2^32).
struct CanCounters {
    std::uint32_t received{0};        ///< data frames received
    std::uint32_t sent{0};            ///< frames accepted for sending
    std::uint32_t send_failures{0};   ///< send() calls that did not return ok
    std::uint32_t error_frames{0};    ///< error frames received
    std::uint32_t dropped{0};         ///< frames lost before we read them (kernel/queue overflow)
    std::uint32_t bus_off_events{0};  ///< error frames with kCanErrorBusOff
    std::uint32_t backend_errors{0};  ///< unexpected errors of the backend (errno etc.)
};

/// One receive filter, with the meaning of Linux's CAN_RAW_FILTER: a data frame passes if its
/// identifier format is the filter's (`extended`) and (frame.id & mask) == (id & mask).  A remote
/// frame never passes a filter.  Error frames are not data frames: no filter ever holds them back
/// (the controller's reports always reach the box, as CAN_RAW_ERR_FILTER keeps them on Linux).
struct CanIdFilter {
    std::uint32_t id{0};
    std::uint32_t mask{kCanStandardIdMask};  ///< kCanStandardIdMask: exactly this 11-bit id
    bool extended{false};
};

/// Filters one receiver holds at most (a controller's acceptance filter banks are few).
inline constexpr std::size_t kCanMaxReceiveFilters = 8;

/// A receiver's filter set (fixed capacity, no heap).  No filter (count 0): every frame passes.
struct CanReceiveFilter {
    std::array<CanIdFilter, kCanMaxReceiveFilters> filters{};
    std::size_t count{0};

    /// False (and nothing changed) if there are more than kCanMaxReceiveFilters.
    constexpr bool assign(std::span<const CanIdFilter> wanted) {
        if (wanted.size() > kCanMaxReceiveFilters) {
            return false;
        }
        count = 0;
        for (const CanIdFilter& filter : wanted) {  // bound: kCanMaxReceiveFilters
            filters[count] = filter;
            ++count;
        }
        return true;
    }

    /// True if `frame` reaches the receiver (see CanIdFilter).
    [[nodiscard]] constexpr bool passes(const CanFrame& frame) const {
        if (frame.error || count == 0U) {
            return true;
        }
        if (frame.remote) {
            return false;
        }
        const std::uint32_t width = frame.extended ? kCanExtendedIdMask : kCanStandardIdMask;
        for (std::size_t i = 0; i < count && i < kCanMaxReceiveFilters; ++i) {  // bound: 8
            const CanIdFilter& filter = filters[i];
            const std::uint32_t mask = filter.mask & width;
            if (filter.extended == frame.extended && (frame.id & mask) == (filter.id & mask)) {
                return true;
            }
        }
        return false;
    }
};

class CanBus {
public:
    /// Queues `frame` for sending, waiting at most `timeout_us` for room.
    virtual CanStatus send(const CanFrame& frame, std::uint32_t timeout_us) = 0;
    /// Takes the next received frame (data or error frame), waiting at most `timeout_us`.
    virtual CanStatus receive(ReceivedCanFrame& received, std::uint32_t timeout_us) = 0;
    [[nodiscard]] virtual CanCounters counters() const = 0;
    /// From now on only data frames that pass one of `filters` (CanIdFilter) are received; an
    /// empty span receives every frame.  Frames already queued stay queued.  Frames held back
    /// are never counted (not received, not dropped), as a kernel or controller filter drops them
    /// before any queue.  Returns ok if the backend filters as asked; invalid for more than
    /// kCanMaxReceiveFilters filters; failed if it cannot filter: it then receives every frame
    /// (the default, for a backend without filters).
    virtual CanStatus set_receive_filter(std::span<const CanIdFilter> filters) {
        (void)filters;
        return CanStatus::failed;
    }

protected:
    CanBus() = default;
    ~CanBus() = default;
    CanBus(const CanBus&) = default;
    CanBus& operator=(const CanBus&) = default;
};

/// Counts one received frame in `counters` (backends share this bookkeeping).
constexpr void count_received_frame(CanCounters& counters, const CanFrame& frame) {
    if (frame.error) {
        ++counters.error_frames;
        if ((frame.id & kCanErrorBusOff) != 0U) {
            ++counters.bus_off_events;
        }
    } else {
        ++counters.received;
    }
}

/// True if `frame` is something a classic CAN controller can send (length, id range).
[[nodiscard]] constexpr bool is_valid_can_frame(const CanFrame& frame) {
    if (frame.length > kCanMaxLength) {
        return false;
    }
    if (frame.error) {
        return true;
    }
    return frame.extended ? frame.id <= kCanExtendedIdMask : frame.id <= kCanStandardIdMask;
}

}  // namespace scopekin::hal
