// loopback_serial.hpp — an in-memory serial line: the simulated device writes bytes, the box's
// driver reads them through hal::SerialPort.  Deterministic; a fixed-capacity ring
// (kLoopbackSerialCapacity bytes); bytes written into a full ring are lost and counted as
// overruns, as a UART's receiver would lose them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hal/serial_port.hpp"

namespace scopekin::hal {

inline constexpr std::size_t kLoopbackSerialCapacity = 4096;

class LoopbackSerialPort final : public SerialPort {
public:
    explicit LoopbackSerialPort(std::uint32_t baud = 115200) : baud_(baud) {}

    /// The device side: bytes the box will read.  Returns how many fitted.
    std::size_t device_write(std::span<const std::uint8_t> bytes);
    /// The device side: bytes the box wrote.
    std::size_t device_read(std::span<std::uint8_t> buffer);

    SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) override;
    SerialTransfer write(std::span<const std::uint8_t> bytes, std::uint32_t timeout_us) override;
    [[nodiscard]] std::uint32_t baud() const override { return baud_; }
    [[nodiscard]] SerialCounters counters() const override { return counters_; }

private:
    struct Ring {
        std::array<std::uint8_t, kLoopbackSerialCapacity> bytes{};
        std::size_t head{0};
        std::size_t count{0};
    };
    static std::size_t put(Ring& ring, std::span<const std::uint8_t> bytes);
    static std::size_t take(Ring& ring, std::span<std::uint8_t> buffer);

    std::uint32_t baud_;
    Ring to_box_{};
    Ring from_box_{};
    SerialCounters counters_{};
};

}  // namespace scopekin::hal
