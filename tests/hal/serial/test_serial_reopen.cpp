// ReopeningSerialPort (hal/posix_serial) on real pseudo-terminals: a serial adapter that is
// unplugged and plugged back in (hosted presets).
//
// The "adapter" is a pty whose slave is reached through a symlink, the way a udev link
// (/dev/serial/by-id/...) names a USB adapter: unplugging closes the master (the slave then reads
// EIO / POLLHUP, a hang-up), plugging in creates a new pty and re-points the link.  The tests
// check that the port reports the outage as `closed` at once, tries to reopen the same path at
// most once per retry interval, reopens it when it is back and reads the new device's bytes; and
// that the EM tracker driver on top flags the outage (kEmFaultSerial, BoxStatus.TrackerFaults'
// link bit) within a period, in every period of it, and clears the flag in the first period after
// the reopen, with samples flowing again.  Time is a test clock, so the retry schedule is exact.
#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include <gtest/gtest.h>

#include "drivers/em_tracker_driver.hpp"
#include "hal/clock.hpp"
#include "hal/posix_serial/reopening_serial_port.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

using scopekin::drivers::EmTrackerDriver;
using scopekin::drivers::EmTrackerDriverConfig;
using scopekin::hal::ReopeningSerialPort;
using scopekin::hal::SerialStatus;

class TestClock final : public scopekin::hal::MonotonicClock {
public:
    [[nodiscard]] std::uint64_t now_us() const override { return now_us_; }
    void wait_until_us(std::uint64_t deadline_us) override {
        if (deadline_us > now_us_) now_us_ = deadline_us;
    }
    void advance_us(std::uint64_t us) { now_us_ += us; }

private:
    std::uint64_t now_us_{1'000'000};
};

/// A pseudo-terminal standing in for a USB-serial adapter: the master is the device's far end.
class Adapter {
public:
    Adapter() {
        fd_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
        std::array<char, 128> slave{};
        if (fd_ < 0 || ::grantpt(fd_) != 0 || ::unlockpt(fd_) != 0 ||
            ::ptsname_r(fd_, slave.data(), slave.size()) != 0) {
            error_ = std::string("cannot create a pseudo-terminal: ") + std::strerror(errno);
            unplug();
            return;
        }
        slave_ = slave.data();
    }
    ~Adapter() { unplug(); }
    Adapter(const Adapter&) = delete;
    Adapter& operator=(const Adapter&) = delete;

    [[nodiscard]] bool ok() const { return fd_ >= 0; }
    [[nodiscard]] const std::string& error() const { return error_; }
    [[nodiscard]] const std::string& slave_path() const { return slave_; }
    /// The adapter is pulled out: the slave side hangs up.
    void unplug() {
        if (fd_ >= 0) {
            ::close(fd_);
            fd_ = -1;
        }
    }
    bool send(std::span<const std::uint8_t> bytes) const {
        return ::write(fd_, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size());
    }

private:
    int fd_{-1};
    std::string slave_;
    std::string error_;
};

/// A temporary folder holding the stable name of the adapter (a symlink), removed at the end.
class StableName {
public:
    StableName() {
        std::array<char, 64> folder{};
        std::snprintf(folder.data(), folder.size(), "/tmp/scopekin_reopen_XXXXXX");
        if (::mkdtemp(folder.data()) != nullptr) {
            folder_ = folder.data();
            path_ = folder_ + "/ttyEM0";
        }
    }
    ~StableName() {
        if (!folder_.empty()) {
            std::error_code ignored;
            std::filesystem::remove_all(folder_, ignored);
        }
    }
    StableName(const StableName&) = delete;
    StableName& operator=(const StableName&) = delete;

    [[nodiscard]] const std::string& path() const { return path_; }
    /// Points the name at `target` (atomically, as udev does).
    bool point_to(const std::string& target) const {
        const std::string temporary = path_ + ".new";
        std::filesystem::remove(temporary);
        return ::symlink(target.c_str(), temporary.c_str()) == 0 &&
               ::rename(temporary.c_str(), path_.c_str()) == 0;
    }
    void remove() const { std::filesystem::remove(path_); }

private:
    std::string folder_;
    std::string path_;
};

constexpr std::uint32_t kRetryUs = 100'000;  // 100 ms
constexpr std::uint64_t kPeriodUs = 5'000;   // the box's period

std::size_t read_all(ReopeningSerialPort& port, std::span<std::uint8_t> buffer,
                     SerialStatus& status) {
    const scopekin::hal::SerialTransfer transfer = port.read(buffer, 200'000U);
    status = transfer.status;
    return transfer.count;
}

}  // namespace

TEST(ReopeningSerialPort, ReopensTheSamePathAtMostOncePerIntervalAfterAHangUp) {
    TestClock clock;
    StableName name;
    ASSERT_FALSE(name.path().empty());
    auto first = std::make_unique<Adapter>();
    ASSERT_TRUE(first->ok()) << first->error();
    ASSERT_TRUE(name.point_to(first->slave_path()));

    ReopeningSerialPort port(clock);
    std::array<char, 256> error{};
    ASSERT_TRUE(port.open(name.path().c_str(), 115200U, kRetryUs, error)) << error.data();
    EXPECT_TRUE(port.device_open());
    EXPECT_EQ(port.baud(), 115200U);

    const std::array<std::uint8_t, 3> before{0xA5, 0x5A, 0x01};
    ASSERT_TRUE(first->send(before));
    std::array<std::uint8_t, 64> buffer{};
    SerialStatus status{};
    EXPECT_EQ(read_all(port, buffer, status), before.size());
    EXPECT_EQ(status, SerialStatus::ok);

    // Unplugged: the master closes and the stable name goes away.
    first->unplug();
    name.remove();
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::closed);
    EXPECT_FALSE(port.device_open());
    EXPECT_EQ(port.reopen_counters().hangups, 1U);
    // Within the retry interval: no attempt at all, still closed (also for writes).
    clock.advance_us(kRetryUs - 1U);
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::closed);
    EXPECT_EQ(port.write(before, 0U).status, SerialStatus::closed);
    EXPECT_EQ(port.reopen_counters().reopen_attempts, 0U);
    // One interval after the hang-up: one attempt, which fails (nothing there) and says why.
    clock.advance_us(1U);
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::closed);
    EXPECT_EQ(port.reopen_counters().reopen_attempts, 1U);
    EXPECT_NE(std::string(port.last_reopen_error()).find(name.path()), std::string::npos)
        << port.last_reopen_error();
    for (int call = 0; call < 50; ++call) {  // many calls, one interval: no further attempt
        EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::closed);
    }
    EXPECT_EQ(port.reopen_counters().reopen_attempts, 1U);

    // Plugged back in: a new pty under the same name.  The next attempt (one interval after the
    // last) opens it; bytes written from then on arrive.
    Adapter second;
    ASSERT_TRUE(second.ok()) << second.error();
    ASSERT_TRUE(name.point_to(second.slave_path()));
    clock.advance_us(kRetryUs / 2U);
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::closed);
    EXPECT_EQ(port.reopen_counters().reopens, 0U);
    clock.advance_us(kRetryUs / 2U);
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::timeout);  // open, nothing yet
    EXPECT_TRUE(port.device_open());
    EXPECT_EQ(port.reopen_counters().reopen_attempts, 2U);
    EXPECT_EQ(port.reopen_counters().reopens, 1U);
    const std::array<std::uint8_t, 5> after{1, 2, 3, 4, 5};
    ASSERT_TRUE(second.send(after));
    EXPECT_EQ(read_all(port, buffer, status), after.size());
    EXPECT_EQ(status, SerialStatus::ok);
    EXPECT_TRUE(std::equal(after.begin(), after.end(), buffer.begin()));
    // The counters add up over both sessions.
    EXPECT_EQ(port.counters().bytes_received, before.size() + after.size());
    EXPECT_EQ(port.reopen_counters().hangups, 1U);
}

TEST(ReopeningSerialPort, OpenRefusesWhatPosixSerialPortRefusesAndOverlongPaths) {
    TestClock clock;
    ReopeningSerialPort port(clock);
    std::array<char, 256> error{};
    EXPECT_FALSE(port.open("/nonexistent/ttyEM0", 115200U, kRetryUs, error));
    EXPECT_NE(std::string(error.data()).find("/nonexistent/ttyEM0"), std::string::npos);
    const std::string overlong(ReopeningSerialPort::kMaxPathLength + 1U, 'x');
    EXPECT_FALSE(port.open(overlong.c_str(), 115200U, kRetryUs, error));
    EXPECT_NE(std::string(error.data()).find("more than"), std::string::npos) << error.data();
    // Never opened: reads fail (there is no device to wait for) and nothing is retried.
    std::array<std::uint8_t, 8> buffer{};
    clock.advance_us(10U * kRetryUs);
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::failed);
    EXPECT_EQ(port.reopen_counters().reopen_attempts, 0U);
}

// The box's view: the EM tracker driver serviced once per 5 ms period on the reopening port.
TEST(ReopeningSerialPort, TrackerLinkFaultFlaggedDuringTheOutageAndClearedAfterTheReopen) {
    TestClock clock;
    StableName name;
    ASSERT_FALSE(name.path().empty());
    auto adapter = std::make_unique<Adapter>();
    ASSERT_TRUE(adapter->ok()) << adapter->error();
    ASSERT_TRUE(name.point_to(adapter->slave_path()));
    ReopeningSerialPort port(clock);
    std::array<char, 256> error{};
    ASSERT_TRUE(port.open(name.path().c_str(), 115200U, kRetryUs, error)) << error.data();

    EmTrackerDriverConfig config;
    config.monitored_sources = scopekin::messages::kEmSourceTipForce;
    EmTrackerDriver driver(config);
    std::uint32_t device_time_us = 0;
    // One period: the tracker sends a tip force frame (if plugged in), the box services the
    // driver; returns the period's fault flags.
    auto period = [&](Adapter* sender) {
        if (sender != nullptr) {
            scopekin::protocol::TipForceMessage message;
            device_time_us += 5000U;
            message.device_time_us = device_time_us;
            message.force_mN = {100, -200, 300};
            std::array<std::uint8_t, scopekin::protocol::kEmTrackerMaxFrameSize> frame{};
            const std::size_t size = scopekin::protocol::encode_tip_force(message, frame);
            EXPECT_TRUE(sender->send(std::span<const std::uint8_t>{frame.data(), size}));
            ::usleep(2000);  // let the pty deliver (the box's period leaves the same room)
        }
        clock.advance_us(kPeriodUs);
        (void)driver.service(port, clock.now_us());
        return driver.take_fault_flags();
    };

    for (int k = 0; k < 10; ++k) {
        period(adapter.get());
    }
    EXPECT_EQ(period(adapter.get()), 0U) << "healthy before the outage";
    const std::uint32_t forces_before = driver.counters().tip_forces_ok;
    EXPECT_GE(forces_before, 10U);

    adapter->unplug();
    name.remove();
    // Flagged in the first period after the unplug, and in every period of the outage.
    int outage_periods = 0;
    for (; outage_periods < 60; ++outage_periods) {
        const std::uint32_t flags = period(nullptr);
        ASSERT_NE(flags & scopekin::messages::kEmFaultSerial, 0U)
            << "period " << outage_periods << " of the outage";
    }
    EXPECT_GE(port.reopen_counters().reopen_attempts, 2U);  // 300 ms / 100 ms, bounded
    EXPECT_LE(port.reopen_counters().reopen_attempts, 3U);

    // Plugged back in: cleared in the first period after the reopen, samples flow again.
    Adapter back;
    ASSERT_TRUE(back.ok()) << back.error();
    ASSERT_TRUE(name.point_to(back.slave_path()));
    const std::uint32_t reopens_before = port.reopen_counters().reopens;
    int periods_to_reopen = 0;
    while (port.reopen_counters().reopens == reopens_before && periods_to_reopen < 40) {
        period(nullptr);
        ++periods_to_reopen;
    }
    ASSERT_EQ(port.reopen_counters().reopens, reopens_before + 1U);
    EXPECT_LE(static_cast<std::uint64_t>(periods_to_reopen) * kPeriodUs, kRetryUs + kPeriodUs);
    int periods_to_clear = 0;
    std::uint32_t flags = 0;
    do {
        flags = period(&back);
        ++periods_to_clear;
    } while (flags != 0U && periods_to_clear < 10);
    EXPECT_EQ(flags, 0U);
    EXPECT_LE(periods_to_clear, 3);
    EXPECT_GT(driver.counters().tip_forces_ok, forces_before);
    EXPECT_FALSE(driver.tip_force_stale());
}
