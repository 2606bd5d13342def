// cmsdk_uart.cpp — see cmsdk_uart.hpp.
#include "hal/bare_metal/cmsdk_uart.hpp"

namespace scopekin::hal {

namespace {
constexpr std::uintptr_t kData = 0x000U;
constexpr std::uintptr_t kState = 0x004U;
constexpr std::uintptr_t kCtrl = 0x008U;
constexpr std::uintptr_t kBaudDiv = 0x010U;
constexpr std::uint32_t kStateTxFull = 1U << 0U;
constexpr std::uint32_t kStateRxFull = 1U << 1U;
constexpr std::uint32_t kStateRxOverrun = 1U << 3U;
constexpr std::uint32_t kCtrlTxEnable = 1U << 0U;
constexpr std::uint32_t kCtrlRxEnable = 1U << 1U;
constexpr std::uint32_t kMinBaudDiv = 16U;  // the CMSDK UART's minimum divider

volatile std::uint32_t& reg(std::uintptr_t address) {
    return *reinterpret_cast<volatile std::uint32_t*>(address);
}
}  // namespace

CmsdkUart::CmsdkUart(std::uintptr_t base, std::uint32_t baud, std::uint32_t pclk_hz,
                     MonotonicClock* clock)
    : base_(base), baud_(baud == 0U ? 115200U : baud), clock_(clock) {
    const std::uint32_t divider = pclk_hz / baud_;
    reg(base_ + kBaudDiv) = divider < kMinBaudDiv ? kMinBaudDiv : divider;
    reg(base_ + kCtrl) = kCtrlTxEnable | kCtrlRxEnable;
}

bool CmsdkUart::deadline_passed(std::uint64_t deadline_us) const {
    return clock_ == nullptr || clock_->now_us() >= deadline_us;
}

SerialTransfer CmsdkUart::read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) {
    const std::uint64_t deadline = clock_ != nullptr ? clock_->now_us() + timeout_us : 0U;
    std::size_t count = 0;
    // Bounded: at most buffer.size() bytes, and the wait for the first one by the deadline.
    while (count < buffer.size()) {
        const std::uint32_t state = reg(base_ + kState);
        if ((state & kStateRxOverrun) != 0U) {
            ++counters_.overruns;
            reg(base_ + kState) = kStateRxOverrun;  // write 1 to clear
        }
        if ((state & kStateRxFull) != 0U) {
            buffer[count++] = static_cast<std::uint8_t>(reg(base_ + kData) & 0xFFU);
            continue;
        }
        if (count > 0U || deadline_passed(deadline)) {
            break;
        }
    }
    counters_.bytes_received += static_cast<std::uint32_t>(count);
    return SerialTransfer{count > 0U ? SerialStatus::ok : SerialStatus::timeout, count};
}

SerialTransfer CmsdkUart::write(std::span<const std::uint8_t> bytes, std::uint32_t timeout_us) {
    const std::uint64_t deadline = clock_ != nullptr ? clock_->now_us() + timeout_us : 0U;
    std::size_t count = 0;
    while (count < bytes.size()) {  // bounded by the byte count and the deadline
        if ((reg(base_ + kState) & kStateTxFull) == 0U) {
            reg(base_ + kData) = bytes[count++];
            continue;
        }
        if (deadline_passed(deadline)) {
            break;
        }
    }
    counters_.bytes_sent += static_cast<std::uint32_t>(count);
    return SerialTransfer{count > 0U || bytes.empty() ? SerialStatus::ok : SerialStatus::timeout,
                          count};
}

}  // namespace scopekin::hal
