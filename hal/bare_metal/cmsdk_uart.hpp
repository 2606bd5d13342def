// cmsdk_uart.hpp — hal::SerialPort on an Arm CMSDK APB UART (the UARTs of the MPS2 boards;
// mps2-an386 UART0 at 0x40004000), polled.  Registers (Arm DDI 0479, CMSDK APB UART):
//   0x000 DATA, 0x004 STATE (bit 0 TX full, bit 1 RX full, bit 2 TX overrun, bit 3 RX overrun;
//   write 1 to clear an overrun), 0x008 CTRL (bit 0 TX enable, bit 1 RX enable), 0x010 BAUDDIV.
// The UART has a one-byte receive buffer: the executive must poll it at least once per byte time
// (87 µs at 115200 bit/s) or bytes are lost (counted as overruns) — a production board would
// use the RX interrupt into a ring; the interface stays the same.
// Timeouts need a clock: with none (nullptr), every call polls once (timeout 0).
#pragma once

#include <cstdint>
#include <span>

#include "hal/clock.hpp"
#include "hal/serial_port.hpp"

namespace scopekin::hal {

class CmsdkUart final : public SerialPort {
public:
    static constexpr std::uintptr_t kMps2Uart0 = 0x40004000U;

    /// Enables TX and RX at `baud` from the peripheral clock `pclk_hz` (25 MHz on mps2-an386).
    CmsdkUart(std::uintptr_t base, std::uint32_t baud, std::uint32_t pclk_hz,
              MonotonicClock* clock);

    SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) override;
    SerialTransfer write(std::span<const std::uint8_t> bytes, std::uint32_t timeout_us) override;
    [[nodiscard]] std::uint32_t baud() const override { return baud_; }
    [[nodiscard]] SerialCounters counters() const override { return counters_; }

private:
    [[nodiscard]] bool deadline_passed(std::uint64_t deadline_us) const;

    std::uintptr_t base_;
    std::uint32_t baud_;
    MonotonicClock* clock_;
    SerialCounters counters_{};
};

}  // namespace scopekin::hal
