// box_main.cpp — `main` of the sensor box on a Cortex-M4 (QEMU mps2-an386): the same cyclic
// executive as scopekin-box, on the bare-metal backends: SysTick clock, CMSDK UART0 for the
// test-bench serial sensors, and — the board has no CAN controller — the loopback wire in its
// place.  The wire's far end is played here by a handle-sensor simulator (1 kHz, a
// 50 mm/s advance), so the image is a self-contained demonstration and test: it runs
// kDemoPeriods periods in real (SysTick) time, decodes everything the box published, and exits
// through semihosting with status 0 only if every period published its frames, the estimate
// followed the advance, and no fault other than the unconnected tracker's was raised.
#include <cstdint>

#include "executive/sensor_box.hpp"
#include "hal/bare_metal/cmsdk_uart.hpp"
#include "hal/bare_metal/systick_clock.hpp"
#include "hal/clock.hpp"
#include "hal/loopback/loopback_can.hpp"
#include "kinetics/default_reduced_tables.hpp"
#include "protocol/can/scopekin_messages.hpp"
#include "semihosting.h"

namespace {

using scopekin::fixed_point::Q16_16;
namespace protocol = scopekin::protocol;
namespace hal = scopekin::hal;

constexpr std::uint32_t kPeriodUs = 5000;
constexpr std::uint32_t kDemoPeriods = 100;  // 0.5 s

hal::SysTickClock g_clock{};
hal::LoopbackCanWire g_wire{g_clock};
hal::CmsdkUart g_uart{hal::CmsdkUart::kMps2Uart0, 115200U, 25'000'000U, &g_clock};
scopekin::executive::SensorBox g_box{};

void write_number(const char* label, std::uint32_t value) {
    char text[16] = {};
    int n = 0;
    do {
        text[n++] = static_cast<char>('0' + value % 10U);
        value /= 10U;
    } while (value != 0U && n < 15);
    char line[64] = {};
    int pos = 0;
    for (const char* c = label; *c != '\0' && pos < 40; ++c)
        line[pos++] = *c;
    while (n > 0)
        line[pos++] = text[--n];
    line[pos++] = '\n';
    scopekin_semihost_write0(line);
}

}  // namespace

int main() {
    scopekin::executive::BoxConfig config{};
    config.period_us = kPeriodUs;
    config.kinetics = scopekin::kinetics::default_config();  // the default tables and trees
    config.em_tracker.monitored_sources = 0;  // no tracker on this board: nothing can go stale
    const bool estimator_ok = g_box.init(config, g_wire.box(), &g_uart);

    hal::PeriodicTimer timer(g_clock, kPeriodUs);
    Q16_16 insertion = Q16_16::from_int(100);
    std::uint8_t counter = 0;
    std::uint32_t estimates = 0;
    std::uint32_t alarms = 0;
    std::uint32_t statuses = 0;
    protocol::KineticEstimate last{};
    for (std::uint32_t period = 0; period < kDemoPeriods; ++period) {  // bound: kDemoPeriods
        // The handle sensors' millisecond frames of the period that ends now.
        for (int ms = 0; ms < 5; ++ms) {
            insertion = scopekin::fixed_point::add_sat(insertion, Q16_16::from_ratio(1, 20));
            protocol::HandleForceTorque force{};
            force.force_N = Q16_16::from_int(2);
            force.counter = counter;
            protocol::InsertionRoll encoder{};
            encoder.insertion_mm = insertion;
            encoder.counter = counter;
            counter = static_cast<std::uint8_t>((counter + 1U) % 16U);
            (void)g_wire.world().send(protocol::encode(force), 0);
            (void)g_wire.world().send(protocol::encode(encoder), 0);
        }
        (void)timer.wait_next();
        g_box.run_period(g_clock.now_us(), timer.overruns());
        hal::ReceivedCanFrame received{};
        for (int n = 0; n < 16 && g_wire.world().receive(received, 0) == hal::CanStatus::ok; ++n) {
            if (protocol::decode(received.frame, last) == protocol::DecodeResult::ok) ++estimates;
            if (received.frame.id == protocol::kAlarmsId) ++alarms;
            if (received.frame.id == protocol::kBoxStatusId) ++statuses;
        }
    }
    write_number("box periods: ", g_box.counters().periods);
    write_number("estimates published: ", estimates);
    write_number("alarm frames published: ", alarms);
    write_number("status frames published: ", statuses);
    write_number("frames read: ", g_box.counters().frames_read);
    write_number("period overruns: ", timer.overruns());
    write_number("tip path (0.1 mm): ", static_cast<std::uint32_t>(last.tip_path_mm.raw() / 6554));
    write_number("driver faults: ", g_box.box_faults());
    const bool ok = estimator_ok && estimates == kDemoPeriods && alarms == kDemoPeriods &&
                    statuses >= kDemoPeriods / 20U && last.estimate_valid && !last.inputs_stale &&
                    last.tip_path_mm > Q16_16::from_int(50) && g_box.box_faults() == 0U &&
                    g_box.counters().frames_read == 2U * 5U * kDemoPeriods;
    scopekin_semihost_write0(ok ? "scopekin box (cortex-m4): PASS\n"
                                : "scopekin box (cortex-m4): FAIL\n");
    return ok ? 0 : 1;
}
