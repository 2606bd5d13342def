// The POSIX serial backend and the EM tracker driver against a real pseudo-terminal (hosted
// presets: host, asan, aarch64 under qemu-aarch64).
//
// A simulated EM tracker (a thread) writes a hostile byte stream — valid frames, noise, corrupted
// and truncated frames, fake headers — into the pty's master side in random chunk sizes with small
// delays; the driver reads the slave side through PosixSerialPort (raw mode) as a hal::SerialPort
// and must deliver exactly the valid frames' samples, in order.  Also: open errors, raw mode
// (every byte value passes both ways unchanged), timeouts, hang-up -> closed.
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "drivers/em_tracker_driver.hpp"
#include "em_tracker_sample_match.hpp"
#include "em_tracker_stream.hpp"
#include "hal/posix_serial/posix_serial_port.hpp"

namespace {

using scopekin::drivers::EmTrackerDriver;
using scopekin::hal::PosixSerialPort;
using scopekin::hal::SerialPort;
using scopekin::hal::SerialStatus;
using scopekin::hal::SerialTransfer;
using scopekin::messages::EmTrackerSample;
using Clock = std::chrono::steady_clock;

std::uint64_t now_us() {
    return static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
            .count());
}

/// The master side of a pseudo-terminal (non-blocking; the slave is opened by PosixSerialPort).
class PtyMaster {
public:
    PtyMaster() {
        fd_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
        if (fd_ < 0 || ::grantpt(fd_) != 0 || ::unlockpt(fd_) != 0 ||
            ::ptsname_r(fd_, slave_path_.data(), slave_path_.size()) != 0) {
            error_ = std::string("cannot create a pseudo-terminal: ") + std::strerror(errno);
            close();
            return;
        }
        const int flags = ::fcntl(fd_, F_GETFL);
        ::fcntl(fd_, F_SETFL, flags | O_NONBLOCK);
    }
    ~PtyMaster() { close(); }
    PtyMaster(const PtyMaster&) = delete;
    PtyMaster& operator=(const PtyMaster&) = delete;

    [[nodiscard]] bool ok() const { return fd_ >= 0; }
    [[nodiscard]] const std::string& error() const { return error_; }
    [[nodiscard]] const char* slave_path() const { return slave_path_.data(); }
    void close() {
        if (fd_ >= 0) {
            ::close(fd_);
            fd_ = -1;
        }
    }

    /// Writes everything unless `stop` is set or `deadline` passes; false if it could not.
    bool write_all(std::span<const std::uint8_t> bytes, const std::atomic<bool>& stop,
                   Clock::time_point deadline) const {
        std::size_t offset = 0;
        while (offset < bytes.size()) {
            if (stop.load() || Clock::now() > deadline) {
                return false;
            }
            const ssize_t written = ::write(fd_, bytes.data() + offset, bytes.size() - offset);
            if (written > 0) {
                offset += static_cast<std::size_t>(written);
                continue;
            }
            if (written < 0 && errno != EAGAIN && errno != EINTR) {
                return false;
            }
            pollfd descriptor{fd_, POLLOUT, 0};
            ::poll(&descriptor, 1, 20);  // the slave's input queue is full: the reader drains it
        }
        return true;
    }

    /// Reads exactly `count` bytes within `timeout`, or fewer if they do not come.
    std::vector<std::uint8_t> read_some(std::size_t count,
                                        std::chrono::milliseconds timeout) const {
        std::vector<std::uint8_t> bytes;
        const auto deadline = Clock::now() + timeout;
        std::array<std::uint8_t, 512> buffer{};
        while (bytes.size() < count && Clock::now() < deadline) {
            pollfd descriptor{fd_, POLLIN, 0};
            if (::poll(&descriptor, 1, 20) <= 0) {
                continue;
            }
            const ssize_t got =
                ::read(fd_, buffer.data(), std::min(buffer.size(), count - bytes.size()));
            if (got > 0) {
                bytes.insert(bytes.end(), buffer.begin(), buffer.begin() + got);
            }
        }
        return bytes;
    }

private:
    int fd_{-1};
    std::array<char, 128> slave_path_{};
    std::string error_;
};

std::string message(const std::array<char, 256>& error) {
    return std::string(error.data());
}

/// Opens `port` on the slave side of `master` at 115200 baud (raw mode); says why not.
::testing::AssertionResult open_on_pty(const PtyMaster& master, PosixSerialPort& port) {
    if (!master.ok()) {
        return ::testing::AssertionFailure() << master.error();
    }
    std::array<char, 256> error{};
    if (!port.open(master.slave_path(), 115200U, error)) {
        return ::testing::AssertionFailure() << message(error);
    }
    return ::testing::AssertionSuccess();
}

}  // namespace

TEST(PosixSerialPort, OpenNamesTheDeviceAndTheCause) {
    PosixSerialPort port;
    std::array<char, 256> error{};
    EXPECT_FALSE(port.open("/nonexistent/ttyEM0", 115200U, error));
    EXPECT_FALSE(port.is_open());
    EXPECT_NE(message(error).find("/nonexistent/ttyEM0"), std::string::npos) << message(error);
    EXPECT_NE(message(error).find(std::strerror(ENOENT)), std::string::npos) << message(error);

    EXPECT_FALSE(port.open("/dev/null", 115200U, error));
    EXPECT_NE(message(error).find("/dev/null"), std::string::npos) << message(error);
    EXPECT_NE(message(error).find("not a terminal"), std::string::npos) << message(error);

    EXPECT_FALSE(port.open(nullptr, 115200U, error));
    EXPECT_NE(message(error).find("no device path"), std::string::npos) << message(error);

    // Not open: transfers fail (and are counted), nothing crashes.
    std::array<std::uint8_t, 4> buffer{};
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::failed);
    EXPECT_EQ(port.write(buffer, 0U).status, SerialStatus::failed);
    EXPECT_EQ(port.counters().backend_errors, 2U);
}

TEST(PosixSerialPort, UnsupportedBaudRateIsAClearError) {
    PtyMaster master;
    ASSERT_TRUE(master.ok()) << master.error();
    PosixSerialPort port;
    std::array<char, 256> error{};
    EXPECT_FALSE(port.open(master.slave_path(), 12345U, error));
    EXPECT_NE(message(error).find("unsupported baud rate 12345"), std::string::npos)
        << message(error);
    EXPECT_NE(message(error).find(master.slave_path()), std::string::npos) << message(error);
    EXPECT_FALSE(port.is_open());
    EXPECT_EQ(port.baud(), 0U);

    const auto bauds = PosixSerialPort::supported_bauds();
    ASSERT_FALSE(bauds.empty());
    // Rates a pseudo-terminal accepts everywhere: qemu-user 7.2 (the aarch64 preset) translates
    // termios speeds only up to B460800, so 921600 fails there (open() reports it as "did not
    // accept the settings", which is the right answer for a device that does that).
    for (const std::uint32_t baud : {9600U, 57600U, 115200U, 460800U}) {
        EXPECT_NE(std::find(bauds.begin(), bauds.end(), baud), bauds.end()) << baud;
        EXPECT_TRUE(port.open(master.slave_path(), baud, error)) << message(error);
        EXPECT_EQ(port.baud(), baud);
    }
}

TEST(PosixSerialPort, RawModePassesEveryByteValueBothWays) {
    PtyMaster master;
    PosixSerialPort port;
    ASSERT_TRUE(open_on_pty(master, port));

    std::array<std::uint8_t, 256> all{};
    for (std::size_t i = 0; i < all.size(); ++i) {
        all[i] = static_cast<std::uint8_t>(i);  // CR, LF, XON/XOFF, ^C, ^D, DEL, 0xFF ...
    }
    // Box -> tracker: no output processing (no LF -> CRLF).
    const SerialTransfer sent = port.write(all, 1'000'000U);
    EXPECT_EQ(sent.status, SerialStatus::ok);
    EXPECT_EQ(sent.count, all.size());
    const std::vector<std::uint8_t> at_master =
        master.read_some(all.size(), std::chrono::seconds(2));
    EXPECT_EQ(at_master, std::vector<std::uint8_t>(all.begin(), all.end()));

    // Tracker -> box: no input processing (no CR -> LF, no signals, no echo, no EOF on ^D).
    const std::atomic<bool> stop{false};
    ASSERT_TRUE(master.write_all(all, stop, Clock::now() + std::chrono::seconds(2)));
    std::vector<std::uint8_t> at_port;
    const auto deadline = Clock::now() + std::chrono::seconds(2);
    while (at_port.size() < all.size() && Clock::now() < deadline) {
        std::array<std::uint8_t, 100> buffer{};
        const SerialTransfer got = port.read(buffer, 100'000U);
        ASSERT_NE(got.status, SerialStatus::failed);
        ASSERT_NE(got.status, SerialStatus::closed);
        at_port.insert(at_port.end(), buffer.begin(),
                       buffer.begin() + static_cast<std::ptrdiff_t>(got.count));
    }
    EXPECT_EQ(at_port, std::vector<std::uint8_t>(all.begin(), all.end()));
    // Nothing was echoed back to the master.
    EXPECT_TRUE(master.read_some(1, std::chrono::milliseconds(50)).empty());
    EXPECT_EQ(port.counters().bytes_sent, 256U);
    EXPECT_EQ(port.counters().bytes_received, 256U);
    EXPECT_EQ(port.counters().backend_errors, 0U);
}

TEST(PosixSerialPort, ReadTimesOutWhenNothingComesAndReportsClosedAfterHangUp) {
    PtyMaster master;
    PosixSerialPort port;
    ASSERT_TRUE(open_on_pty(master, port));
    std::array<std::uint8_t, 16> buffer{};

    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::timeout);
    const auto start = Clock::now();
    const SerialTransfer waited = port.read(buffer, 50'000U);
    const auto elapsed = Clock::now() - start;
    EXPECT_EQ(waited.status, SerialStatus::timeout);
    EXPECT_EQ(waited.count, 0U);
    EXPECT_GE(elapsed, std::chrono::milliseconds(49));
    EXPECT_LT(elapsed, std::chrono::seconds(2));

    // An empty buffer is not a read.
    EXPECT_EQ(port.read(std::span<std::uint8_t>{}, 1'000'000U).status, SerialStatus::ok);

    master.close();
    const auto hang_up = Clock::now();
    EXPECT_EQ(port.read(buffer, 1'000'000U).status, SerialStatus::closed);
    EXPECT_EQ(port.read(buffer, 0U).status, SerialStatus::closed);
    EXPECT_LT(Clock::now() - hang_up,
              std::chrono::milliseconds(500));  // at once, not after the timeout
    EXPECT_EQ(port.counters().backend_errors, 0U);

    // Moving the port moves the descriptor; the moved-from one is closed.
    PosixSerialPort moved(std::move(port));
    EXPECT_TRUE(moved.is_open());
    EXPECT_FALSE(port.is_open());  // NOLINT(bugprone-use-after-move): defined state, by design
    moved.close();
    EXPECT_FALSE(moved.is_open());
}

TEST(EmTrackerOverPty, DriverOutputMatchesTheValidFramesExactly) {
    // The simulated tracker's stream: 1500 hostile events (~34 KB, ~800 valid frames).
    constexpr std::size_t kEvents = 1500;
    std::vector<std::uint8_t> stream(kEvents * scopekin::test::kMaxStreamEventSize);
    std::vector<scopekin::test::ExpectedEmMessage> expected(kEvents);
    scopekin::test::EmTrackerStreamGenerator generator(0x7E57BE4CU);
    std::size_t expected_count = 0;
    stream.resize(scopekin::test::generate_em_tracker_stream(generator, stream, expected, kEvents,
                                                             expected_count));
    expected.resize(expected_count);
    ASSERT_GT(expected_count, kEvents / 2U);

    PtyMaster master;
    PosixSerialPort port;
    // Raw mode is set before the first byte is written (a cooked line would mangle CR, ^C, ...).
    ASSERT_TRUE(open_on_pty(master, port));

    std::atomic<bool> stop{false};
    std::atomic<bool> writer_done{false};
    std::atomic<bool> writer_ok{false};
    const auto deadline = Clock::now() + std::chrono::seconds(8);
    std::thread tracker([&] {
        scopekin::test::TestPrng prng(99U);
        std::size_t offset = 0;
        bool ok = true;
        while (ok && offset < stream.size()) {
            std::size_t chunk = 1U + prng.below(97U);  // split frames anywhere
            chunk = std::min(chunk, stream.size() - offset);
            ok = master.write_all(std::span<const std::uint8_t>{stream}.subspan(offset, chunk),
                                  stop, deadline);
            offset += chunk;
            if (prng.below(4U) == 0U) {
                std::this_thread::sleep_for(std::chrono::microseconds(prng.below(400U)));
            }
        }
        writer_ok = ok;
        writer_done = true;
    });

    // The box's side: service() as a cyclic executive would, through the SerialPort interface.
    EmTrackerDriver driver;
    SerialPort& serial = port;
    std::vector<EmTrackerSample> samples;
    EmTrackerSample sample;
    while (Clock::now() < deadline) {
        const auto result = driver.service(serial, now_us());
        while (driver.pop(sample)) {
            samples.push_back(sample);
        }
        ASSERT_NE(result.status, SerialStatus::failed);
        ASSERT_NE(result.status, SerialStatus::closed);
        // Done when every byte the tracker wrote has been read (and serviced, above).
        if (writer_done && port.counters().bytes_received >= stream.size()) {
            break;
        }
        if (result.bytes_read == 0U) {
            std::this_thread::sleep_for(std::chrono::microseconds(300));
        }
    }
    stop = true;
    tracker.join();
    ASSERT_TRUE(writer_ok) << "the simulated tracker could not write its stream in time";

    ASSERT_EQ(samples.size(), expected.size());
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
        if (!scopekin::test::sample_matches(samples[i], expected[i])) {
            ++mismatches;
            ADD_FAILURE() << "sample " << i << " differs from valid frame " << i;
        }
    }
    EXPECT_EQ(mismatches, 0U);
    const auto counters = driver.counters();
    EXPECT_EQ(counters.link.frames_ok, expected.size());
    EXPECT_EQ(counters.poses_ok + counters.tip_forces_ok, expected.size());
    EXPECT_GT(counters.link.bad_checksum, 0U);
    EXPECT_GT(counters.link.bad_length, 0U);
    EXPECT_GT(counters.link.unknown_type, 0U);
    EXPECT_EQ(counters.link.buffer_overflows, 0U);
    EXPECT_EQ(counters.samples_dropped, 0U);
    EXPECT_EQ(counters.timestamp_backwards, 0U);
    EXPECT_EQ(port.counters().bytes_received, stream.size());
    // Byte accounting: every byte written is in a valid frame, was discarded, or is the start of a
    // frame still waiting for its end (the stream may end with a truncated frame).
    std::size_t frame_bytes = 0;
    for (const auto& message : expected) {
        frame_bytes +=
            message.type == scopekin::protocol::EmTrackerMessageType::pose
                ? scopekin::protocol::kEmTrackerOverhead + scopekin::protocol::kEmPosePayloadSize
                : scopekin::protocol::kEmTrackerOverhead + scopekin::protocol::kTipForcePayloadSize;
    }
    EXPECT_EQ(frame_bytes + counters.link.bytes_discarded + driver.buffered_bytes(), stream.size());

    // The tracker goes away: the driver sees the hang-up, counts and flags it.
    master.close();
    const auto result = driver.service(serial, now_us());
    EXPECT_EQ(result.status, SerialStatus::closed);
    EXPECT_EQ(driver.counters().serial_closed, 1U);
    EXPECT_NE(driver.take_fault_flags() & scopekin::messages::kEmFaultSerial, 0U);
}
