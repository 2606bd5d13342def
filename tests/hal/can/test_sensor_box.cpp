// The box's cyclic executive (firmware/executive/sensor_box) on the loopback HAL, driven by
// simulated time: what it publishes every period, a sensor that stops and returns, error
// frames and bus-off, garbage on the bus that must change nothing but counters (with the box's
// receive filter and on a backend without one), a flood of foreign frames, more frames than a
// period reads and the catch-up after a stall, receive-queue drops and period overruns (each
// flagged within 3 periods, survived, cleared when the cause goes), the test bench's EM tracker
// samples reaching the estimator's input, a saturated 921,600 bit/s tracker line read completely
// every period, and a line of bytes with no sync flagged as a framing fault.
#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>

#include "executive/sensor_box.hpp"
#include "hal/loopback/loopback_can.hpp"
#include "hal/loopback/loopback_serial.hpp"
#include "hal/loopback/simulated_clock.hpp"
#include "kinetics/default_reduced_tables.hpp"
#include "portable_check.hpp"
#include "protocol/can/scopekin_messages.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
namespace protocol = scopekin::protocol;
namespace executive = scopekin::executive;
namespace hal = scopekin::hal;
namespace messages = scopekin::messages;

constexpr std::uint64_t kPeriodUs = 5000;

/// |a - b| <= tolerance, in Q16.16 raw units.
bool within_raw(Q16_16 a, Q16_16 b, std::int64_t tolerance) {
    const std::int64_t d = std::int64_t{a.raw()} - b.raw();
    return d <= tolerance && -d <= tolerance;
}

/// What the world saw the box publish in one period.
struct Published {
    int estimates{0};
    int summaries{0};
    int alarms{0};
    int statuses{0};
    int counters{0};
    int stations{0};
    int evidences{0};
    int other{0};
    protocol::KineticEstimate estimate{};
    protocol::Alarms alarm{};
    protocol::EstimateEvidence evidence{};
    protocol::BoxStatus status{};
};

/// A bench: the box and a world on one loopback wire, simulated time, handle sensors at 1 kHz.
/// Static storage: the wire and the box are large.
struct Bench {
    hal::SimulatedClock clock{0};
    hal::LoopbackCanWire wire{clock};
    executive::SensorBox box{};
    std::uint8_t force_counter{0};
    std::uint8_t insertion_counter{0};
    bool send_force{true};
    bool send_insertion{true};
    Q16_16 insertion_mm = Q16_16::from_int(100);
    Q16_16 speed_mm_per_ms = Q16_16::from_ratio(1, 20);  // 50 mm/s
    std::uint32_t foreign_per_ms{0};  ///< frames of other identifiers, each millisecond
    std::uint32_t overruns{0};        ///< main's count of skipped periods, passed to the box

    void start(hal::SerialPort* serial = nullptr) {
        executive::BoxConfig config{};
        config.period_us = kPeriodUs;
        config.kinetics.tables = &scopekin::kinetics::default_reduced_tables();
        SCOPEKIN_EXPECT_TRUE(box.init(config, wire.box(), serial));
    }

    /// One millisecond of the world: each sensor sends one frame.
    void world_millisecond() {
        clock.advance_by(1000);
        insertion_mm = scopekin::fixed_point::add_sat(insertion_mm, speed_mm_per_ms);
        if (send_force) {
            protocol::HandleForceTorque force{};
            force.force_N = Q16_16::from_int(2);
            force.counter = force_counter;
            force_counter = static_cast<std::uint8_t>((force_counter + 1U) % 16U);
            (void)wire.world().send(protocol::encode(force), 0);
        }
        if (send_insertion) {
            protocol::InsertionRoll insertion{};
            insertion.insertion_mm = insertion_mm;
            insertion.counter = insertion_counter;
            insertion_counter = static_cast<std::uint8_t>((insertion_counter + 1U) % 16U);
            (void)wire.world().send(protocol::encode(insertion), 0);
        }
        for (std::uint32_t j = 0; j < foreign_per_ms; ++j) {  // bound: foreign_per_ms
            hal::CanFrame foreign{};
            foreign.id = 0x300U + j % 0x100U;
            foreign.length = 8;
            (void)wire.world().send(foreign, 0);
        }
    }

    /// `ms` milliseconds of the world with the box not running (a stall); main's timer counts
    /// the periods it skipped.
    void stall(int ms) {
        for (int k = 0; k < ms; ++k) {
            world_millisecond();
        }
        overruns += static_cast<std::uint32_t>(ms / 5);
    }

    /// One period: 5 ms of the world, then the box's period; returns what it published.
    Published period() {
        for (int ms = 0; ms < 5; ++ms) {
            world_millisecond();
        }
        box.run_period(clock.now_us(), overruns);
        Published out{};
        hal::ReceivedCanFrame received{};
        while (wire.world().receive(received, 0) == hal::CanStatus::ok) {
            switch (received.frame.id) {
                case protocol::kKineticEstimateId:
                    ++out.estimates;
                    SCOPEKIN_EXPECT_TRUE(protocol::decode(received.frame, out.estimate) ==
                                         protocol::DecodeResult::ok);
                    break;
                case protocol::kContactSummaryId: ++out.summaries; break;
                case protocol::kAlarmsId:
                    ++out.alarms;
                    SCOPEKIN_EXPECT_TRUE(protocol::decode(received.frame, out.alarm) ==
                                         protocol::DecodeResult::ok);
                    break;
                case protocol::kBoxStatusId:
                    ++out.statuses;
                    SCOPEKIN_EXPECT_TRUE(protocol::decode(received.frame, out.status) ==
                                         protocol::DecodeResult::ok);
                    break;
                case protocol::kBoxCountersId: ++out.counters; break;
                case protocol::kStationForcesId: ++out.stations; break;
                case protocol::kEstimateEvidenceId:
                    ++out.evidences;
                    SCOPEKIN_EXPECT_TRUE(protocol::decode(received.frame, out.evidence) ==
                                         protocol::DecodeResult::ok);
                    break;
                default: ++out.other; break;
            }
        }
        return out;
    }
};

// One bench per test (they cannot be copied: the wire's endpoints point into it).
Bench bench_publish;
Bench bench_stale;
Bench bench_bus_off;
Bench bench_clean;
Bench bench_noisy;
Bench bench_noisy_unfiltered;
Bench bench_tracker;
Bench bench_flood_reference;
Bench bench_flood;
Bench bench_flood_unfiltered;
Bench bench_stall;
Bench bench_short_stall;
Bench bench_dropped;
Bench bench_overrun;
Bench bench_saturated;
Bench bench_no_sync;
hal::LoopbackSerialPort saturated_line{921600};
hal::LoopbackSerialPort no_sync_line{921600};
hal::LoopbackSerialPort tracker_line{};

/// Writes one EM tracker frame of `message` into the line the box reads.
template <typename Message, typename Encode>
void tracker_sends(const Message& message, Encode encode) {
    std::array<std::uint8_t, scopekin::protocol::kEmTrackerMaxFrameSize> bytes{};
    const std::size_t size = encode(message, bytes);
    SCOPEKIN_EXPECT_TRUE(size > 0U);
    SCOPEKIN_EXPECT_EQ(tracker_line.device_write(std::span<const std::uint8_t>{bytes.data(), size}),
                       size);
}

}  // namespace

SCOPEKIN_TEST(SensorBox, PublishesEveryPeriodAndAHeartbeat) {
    Bench& bench = bench_publish;
    bench.start();
    int statuses = 0;
    for (int k = 0; k < 100; ++k) {
        const Published out = bench.period();
        SCOPEKIN_EXPECT_EQ(out.estimates, 1);
        SCOPEKIN_EXPECT_EQ(out.summaries, 1);
        SCOPEKIN_EXPECT_EQ(out.alarms, 1);
        SCOPEKIN_EXPECT_EQ(out.counters, 1);
        SCOPEKIN_EXPECT_EQ(out.evidences, 1);
        SCOPEKIN_EXPECT_EQ(out.other, 0);
        SCOPEKIN_EXPECT_TRUE(out.estimate.estimate_valid);
        // EstimateEvidence carries this period's estimator outputs (within the wire's steps).
        const scopekin::kinetics::Outputs& estimated = bench.box.outputs();
        SCOPEKIN_EXPECT_EQ(out.evidence.step_counter, out.estimate.step_counter);
        SCOPEKIN_EXPECT_EQ(out.evidence.model_self_lock, estimated.model_self_lock_alarm);
        SCOPEKIN_EXPECT_EQ(out.evidence.tip_from_tracker, estimated.tip_from_tracker);
        // Half a wire step, in Q16.16 raw units: 0.0001, 0.01 and 0.001 (can_signal.hpp).
        SCOPEKIN_EXPECT_TRUE(within_raw(out.evidence.loop_score, estimated.loop_score, 4));
        SCOPEKIN_EXPECT_TRUE(within_raw(out.evidence.model_log_likelihood_ratio,
                                        estimated.model_log_likelihood_ratio, 328));
        SCOPEKIN_EXPECT_TRUE(within_raw(out.evidence.max_contact_force_uncertainty_N,
                                        estimated.max_contact_force_uncertainty_N, 33));
        statuses += out.statuses;
    }
    // 100 periods = 0.5 s: the heartbeat every 20 periods (5), plus the first period's fault
    // change at start-up at most.
    SCOPEKIN_EXPECT_TRUE(statuses >= 5 && statuses <= 7);
    const Published out = bench.period();
    SCOPEKIN_EXPECT_TRUE(!out.estimate.inputs_stale);
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), 0);
    SCOPEKIN_EXPECT_TRUE(bench.box.box_state() == protocol::BoxState::running ||
                         bench.box.box_state() == protocol::BoxState::degraded);
    SCOPEKIN_EXPECT_EQ(bench.box.handle_sensors().counters().counter_gaps, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.counters().unknown_ids, 0U);
    // The tip moves: 0.5 s at 50 mm/s moved the handle 25 mm.
    SCOPEKIN_EXPECT_TRUE(out.estimate.tip_path_mm > Q16_16::from_int(50));
}

// "A sensor that stops sending: fault frame within 3 periods, estimate held and flagged,
// recovery when it returns."
SCOPEKIN_TEST(SensorBox, ASensorThatStopsIsFlaggedWithinThreePeriodsAndRecovers) {
    Bench& bench = bench_stale;
    bench.start();
    for (int k = 0; k < 40; ++k) {
        (void)bench.period();
    }
    const Q16_16 tip_before = bench.box.outputs().tip_path_mm;
    bench.send_insertion = false;
    int periods_to_fault = 0;
    bool flagged = false;
    for (int k = 1; k <= 3 && !flagged; ++k) {
        const Published out = bench.period();
        if (out.statuses > 0 &&
            (out.status.kinetic_faults & scopekin::kinetics::kFaultInsertionStale) != 0U) {
            flagged = true;
            periods_to_fault = k;
            SCOPEKIN_EXPECT_TRUE(out.status.state == protocol::BoxState::degraded);
            SCOPEKIN_EXPECT_TRUE(out.estimate.inputs_stale);
        }
    }
    SCOPEKIN_EXPECT_TRUE(flagged);
    SCOPEKIN_EXPECT_TRUE(periods_to_fault >= 1 && periods_to_fault <= 3);
    // Held: the depth does not move while the encoder is silent, and the driver's own stale flag
    // (3 periods) follows.
    Published out{};
    for (int k = 0; k < 20; ++k) {
        out = bench.period();
        SCOPEKIN_EXPECT_TRUE(out.estimate.inputs_stale);
    }
    SCOPEKIN_EXPECT_TRUE((bench.box.box_faults() & messages::kBoxFaultEncoderStale) != 0U);
    const Q16_16 tip_held = bench.box.outputs().tip_path_mm;
    SCOPEKIN_EXPECT_TRUE(tip_held - tip_before < Q16_16::from_int(2));
    // It returns: the flags clear and a BoxStatus says so within 3 periods.
    bench.send_insertion = true;
    bool cleared = false;
    for (int k = 1; k <= 3 && !cleared; ++k) {
        out = bench.period();
        cleared =
            out.statuses > 0 && out.status.kinetic_faults == 0U && out.status.driver_faults == 0U;
    }
    SCOPEKIN_EXPECT_TRUE(cleared);
    SCOPEKIN_EXPECT_TRUE(!out.estimate.inputs_stale);
    SCOPEKIN_EXPECT_EQ(bench.box.handle_sensors().counters().stale_events, 1U);
}

SCOPEKIN_TEST(SensorBox, ErrorFramesAndBusOffAreCountedReportedAndRecovered) {
    Bench& bench = bench_bus_off;
    bench.start();
    for (int k = 0; k < 10; ++k) {
        (void)bench.period();
    }
    // Error-passive, then bus-off: the controller stops sending.
    std::array<std::uint8_t, 8> passive{};
    passive[1] = 0x20;  // CAN_ERR_CRTL_TX_PASSIVE
    bench.wire.box().inject_error(hal::kCanErrorController, passive);
    bench.wire.box().inject_error(hal::kCanErrorBusOff);
    bench.wire.box().set_bus_off(true);
    Published out = bench.period();
    SCOPEKIN_EXPECT_EQ(out.estimates, 0);  // nothing leaves a bus-off controller
    SCOPEKIN_EXPECT_TRUE((bench.box.box_faults() & messages::kBoxFaultBusOff) != 0U);
    SCOPEKIN_EXPECT_TRUE(bench.box.can_health().state() == protocol::CanState::bus_off);
    for (int k = 0; k < 5; ++k) {
        (void)bench.period();
    }
    // Sends fail after the period's faults are taken: they show from the next period on.
    SCOPEKIN_EXPECT_TRUE((bench.box.box_faults() & messages::kBoxFaultSendFailed) != 0U);
    // The controller restarts (e.g. the kernel's restart-ms).
    bench.wire.box().set_bus_off(false);
    bench.wire.box().inject_error(hal::kCanErrorRestarted);
    out = bench.period();
    SCOPEKIN_EXPECT_EQ(out.estimates, 1);
    SCOPEKIN_EXPECT_EQ(out.statuses, 1);  // the fault bits changed: reported at once
    // The first status after the restart reports the worst state since the last one: bus-off.
    SCOPEKIN_EXPECT_TRUE(out.status.can_state == protocol::CanState::bus_off);
    SCOPEKIN_EXPECT_TRUE(bench.box.can_health().state() == protocol::CanState::error_active);
    SCOPEKIN_EXPECT_EQ(bench.box.can_health().bus_off_events(), 1U);
    SCOPEKIN_EXPECT_EQ(bench.box.can_health().recoveries(), 1U);
    SCOPEKIN_EXPECT_EQ(bench.box.can_health().error_frames(), 3U);
    SCOPEKIN_EXPECT_TRUE(bench.box.counters().send_failures >= 24U);  // 6 periods x 4+ frames
    // Later statuses are error-active again.
    for (int k = 0; k < 25; ++k) {
        out = bench.period();
    }
    SCOPEKIN_EXPECT_TRUE(out.status.can_state == protocol::CanState::error_active);
}

// "Never an alarm raised or cleared because of garbage": three boxes see the same handle frames,
// two of them also a stream of garbage, one through the box's receive filter (as SocketCAN and the
// loopback wire give it), one on a backend without filters; every output of every period must be
// identical, and the garbage counted: held back by the filter, or read and counted as unknown.
SCOPEKIN_TEST(SensorBox, GarbageChangesNothingButCounters) {
    Bench& clean = bench_clean;
    Bench& noisy = bench_noisy;
    Bench& unfiltered = bench_noisy_unfiltered;
    unfiltered.wire.box().set_filtering_supported(false);
    clean.start();
    noisy.start();
    unfiltered.start();
    SCOPEKIN_EXPECT_TRUE(noisy.box.receive_filtered());
    SCOPEKIN_EXPECT_TRUE(!unfiltered.box.receive_filtered());
    std::uint32_t seed = 12345;
    auto next = [&seed]() {
        seed = seed * 1664525U + 1013904223U;
        return seed >> 8U;
    };
    std::uint32_t garbage_unknown = 0;
    std::uint32_t garbage_bad_length = 0;
    for (int k = 0; k < 400; ++k) {
        // Garbage first, so it sits between valid frames in the queue.
        for (int g = 0; g < 3; ++g) {
            hal::CanFrame frame{};
            const std::uint32_t kind = next() % 4U;
            frame.length = static_cast<std::uint8_t>(next() % 9U);
            for (auto& byte : frame.data)
                byte = static_cast<std::uint8_t>(next());
            if (kind == 0U) {  // an input id with a wrong length
                frame.id = (next() % 2U) == 0U ? protocol::kHandleForceTorqueId
                                               : protocol::kInsertionRollId;
                frame.length = frame.id == protocol::kHandleForceTorqueId ? 8 : 2;
                ++garbage_bad_length;
            } else if (kind == 1U) {  // an id nobody uses
                frame.id = 0x500U + next() % 0x100U;
                ++garbage_unknown;
            } else if (kind == 2U) {  // the input id as a 29-bit id
                frame.id = protocol::kHandleForceTorqueId;
                frame.extended = true;
                ++garbage_unknown;
            } else {  // a remote request for an input id
                frame.id = protocol::kInsertionRollId;
                frame.remote = true;
                frame.length = 0;
                ++garbage_unknown;
            }
            (void)noisy.wire.world().send(frame, 0);
            (void)unfiltered.wire.world().send(frame, 0);
        }
        const Published a = clean.period();
        const Published b = noisy.period();
        const Published c = unfiltered.period();
        const auto& oa = clean.box.outputs();
        for (const Bench* bench : {&noisy, &unfiltered}) {
            const auto& ob = bench->box.outputs();
            SCOPEKIN_EXPECT_EQ(oa.tip_path_mm.raw(), ob.tip_path_mm.raw());
            SCOPEKIN_EXPECT_EQ(oa.max_contact_force_N.raw(), ob.max_contact_force_N.raw());
            SCOPEKIN_EXPECT_EQ(oa.self_lock_alarm, ob.self_lock_alarm);
            SCOPEKIN_EXPECT_TRUE(oa.contact_force_level == ob.contact_force_level);
            SCOPEKIN_EXPECT_EQ(oa.fault_flags, ob.fault_flags);
        }
        for (const Published* out : {&b, &c}) {
            SCOPEKIN_EXPECT_EQ(a.alarm.self_lock, out->alarm.self_lock);
            SCOPEKIN_EXPECT_EQ(a.alarm.contact_force_level, out->alarm.contact_force_level);
        }
    }
    // Through the filter: the foreign, 29-bit and remote frames never reach the box.
    SCOPEKIN_EXPECT_EQ(noisy.wire.box().filtered(), garbage_unknown);
    SCOPEKIN_EXPECT_EQ(noisy.box.counters().unknown_ids, 0U);
    SCOPEKIN_EXPECT_EQ(noisy.box.handle_sensors().counters().bad_length, garbage_bad_length);
    SCOPEKIN_EXPECT_EQ(noisy.box.handle_sensors().counters().counter_gaps, 0U);
    // Without a filter: read, counted and flagged as unknown.
    SCOPEKIN_EXPECT_EQ(unfiltered.wire.box().filtered(), 0U);
    SCOPEKIN_EXPECT_EQ(unfiltered.box.counters().unknown_ids, garbage_unknown);
    SCOPEKIN_EXPECT_EQ(unfiltered.box.handle_sensors().counters().bad_length, garbage_bad_length);
    SCOPEKIN_EXPECT_EQ(unfiltered.box.handle_sensors().counters().counter_gaps, 0U);
    SCOPEKIN_EXPECT_TRUE((unfiltered.box.box_faults() &
                          (messages::kBoxFaultUnknownId | messages::kBoxFaultBadLength)) != 0U);
}

namespace {

/// Tip estimate of a bench, mm (Q16.16 raw / 2^16).
double tip_mm(const Bench& bench) {
    return static_cast<double>(bench.box.outputs().tip_path_mm.raw()) / 65536.0;
}

bool backlog(const Bench& bench) {
    return (bench.box.box_faults() & messages::kBoxFaultReceiveBacklog) != 0U;
}

bool insertion_held(const Bench& bench) {
    return (bench.box.outputs().fault_flags & scopekin::kinetics::kFaultInsertionStale) != 0U;
}

}  // namespace

// A flood of foreign frames: 100 per millisecond beside the handle sensors' 2 (500 a period; the
// box reads at most 128 a period, the loopback queue holds 1024).  Through the box's receive
// filter the flood never reaches its queue: every output equals a box's without the flood.
// Without a filter the queue backs up: the backlog is flagged within 3 periods, the samples read
// late are held, not taken as live, and when the flood stops the backlog drains and the flags
// clear.
SCOPEKIN_TEST(SensorBox, AFloodOfForeignFramesIsFilteredOrFlagged) {
    Bench& reference = bench_flood_reference;
    Bench& flood = bench_flood;
    Bench& unfiltered = bench_flood_unfiltered;
    unfiltered.wire.box().set_filtering_supported(false);
    reference.start();
    flood.start();
    unfiltered.start();
    for (int k = 0; k < 40; ++k) {  // 0.2 s without the flood
        (void)reference.period();
        (void)flood.period();
        (void)unfiltered.period();
    }
    const double tip_before_mm = tip_mm(unfiltered);
    flood.foreign_per_ms = 100;
    unfiltered.foreign_per_ms = 100;
    int first_flagged = 0;
    int held_periods = 0;
    for (int k = 1; k <= 100; ++k) {  // 0.5 s of flood
        (void)reference.period();
        const Published filtered_out = flood.period();
        const Published out = unfiltered.period();
        // Filtered: the same outputs, no fault.
        SCOPEKIN_EXPECT_EQ(flood.box.outputs().tip_path_mm.raw(),
                           reference.box.outputs().tip_path_mm.raw());
        SCOPEKIN_EXPECT_EQ(flood.box.outputs().fault_flags, reference.box.outputs().fault_flags);
        SCOPEKIN_EXPECT_EQ(flood.box.box_faults(), reference.box.box_faults());
        SCOPEKIN_EXPECT_EQ(filtered_out.estimates, 1);
        // Unfiltered: flagged from the first period the cap is read, held while backed up.
        if (first_flagged == 0 && backlog(unfiltered)) first_flagged = k;
        if (first_flagged != 0) {
            SCOPEKIN_EXPECT_TRUE(backlog(unfiltered));
        }
        held_periods += insertion_held(unfiltered) ? 1 : 0;
        SCOPEKIN_EXPECT_EQ(out.estimates, 1);  // it keeps publishing
    }
    SCOPEKIN_EXPECT_TRUE(first_flagged >= 1 && first_flagged <= 3);
    SCOPEKIN_EXPECT_EQ(flood.box.counters().unknown_ids, 0U);
    SCOPEKIN_EXPECT_EQ(flood.wire.box().filtered(), 100U * 500U);
    SCOPEKIN_EXPECT_EQ(flood.box.counters().backlog_periods, 0U);
    // The backed-up box took no stale sample as live: its depth was held (the handle moved 25 mm
    // meanwhile), and it says so: inputs stale, backlog counted, the queue's overflow counted.
    SCOPEKIN_EXPECT_TRUE(held_periods >= 90);
    SCOPEKIN_EXPECT_TRUE(tip_mm(unfiltered) - tip_before_mm < 1.0);
    SCOPEKIN_EXPECT_TRUE(unfiltered.box.counters().backlog_periods >= 98U);
    SCOPEKIN_EXPECT_TRUE(unfiltered.box.handle_sensors().counters().late_samples >= 180U);
    SCOPEKIN_EXPECT_TRUE((unfiltered.box.box_faults() & messages::kBoxFaultReceiveDropped) != 0U);
    // The flood stops: the queue (1024 frames) drains at 128 - 10 a period, then the flags clear.
    flood.foreign_per_ms = 0;
    unfiltered.foreign_per_ms = 0;
    int cleared_after = 0;
    for (int k = 1; k <= 20 && cleared_after == 0; ++k) {
        (void)reference.period();
        (void)unfiltered.period();
        if (!backlog(unfiltered) && !insertion_held(unfiltered)) cleared_after = k;
    }
    SCOPEKIN_EXPECT_TRUE(cleared_after >= 1 && cleared_after <= 1024 / (128 - 10) + 2);
    SCOPEKIN_EXPECT_EQ(unfiltered.wire.box().pending(), 0U);
    // ... and the estimate follows the hand again: within 1 mm of the box that never saw a flood
    // after 0.1 s (the depth, 25 mm behind, catches up at the estimator's 1 m/s jump limit: 5 mm
    // a period; measured: equal from the 4th period on).
    for (int k = 0; k < 20; ++k) {
        (void)reference.period();
        (void)unfiltered.period();
    }
    SCOPEKIN_EXPECT_TRUE(tip_mm(unfiltered) - tip_mm(reference) < 1.0);
    SCOPEKIN_EXPECT_TRUE(tip_mm(reference) - tip_mm(unfiltered) < 1.0);
}

// The box not run for 100 ms (main's timer skips 20 periods): with the period's own 5 ms, 210
// handle frames wait, more than the 128 a period reads.  The first period after the stall reads
// its cap: backlog and overrun flagged, the newest sample it read (41 ms old) held, not fresh;
// the next reads the rest (they waited through a period: still a backlog) and fresh samples; the
// third is clean.
SCOPEKIN_TEST(SensorBox, MoreFramesThanAPeriodReadsAfterAStallAreCaughtUp) {
    Bench& bench = bench_stall;
    bench.start();
    for (int k = 0; k < 40; ++k) {
        (void)bench.period();
    }
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), 0);
    const std::uint32_t read_before = bench.box.counters().frames_read;
    bench.stall(100);
    Published out = bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.counters().frames_read - read_before, 128U);
    SCOPEKIN_EXPECT_TRUE(backlog(bench));
    SCOPEKIN_EXPECT_TRUE((bench.box.box_faults() & messages::kBoxFaultPeriodOverrun) != 0U);
    SCOPEKIN_EXPECT_TRUE(insertion_held(bench));  // the newest sample read is 41 ms old
    SCOPEKIN_EXPECT_TRUE(out.estimate.inputs_stale);
    SCOPEKIN_EXPECT_EQ(out.statuses, 1);  // the fault bits changed: reported at once
    SCOPEKIN_EXPECT_TRUE((out.status.driver_faults & messages::kBoxFaultReceiveBacklog) != 0U);
    out = bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.counters().frames_read - read_before, 210U + 10U);
    // The 82 left waited through the last period, 80 of them (ms 65..104 of the 105) more than a
    // period before this one: still a backlog; the newest samples read are fresh again.
    SCOPEKIN_EXPECT_TRUE(backlog(bench));
    SCOPEKIN_EXPECT_TRUE(!insertion_held(bench));
    SCOPEKIN_EXPECT_EQ(bench.box.counters().late_frames, 80U);
    out = bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), 0);
    SCOPEKIN_EXPECT_EQ(out.status.driver_faults, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.counters().backlog_periods, 2U);
    SCOPEKIN_EXPECT_EQ(bench.box.handle_sensors().counters().late_samples, 2U);
    SCOPEKIN_EXPECT_EQ(bench.box.handle_sensors().counters().counter_gaps, 0U);
}

// A 50 ms stall brings 100 frames + 10: under the cap, all read in one period, the newest fresh:
// an overrun (flagged, then cleared), no backlog.
SCOPEKIN_TEST(SensorBox, AShortStallIsAnOverrunNotABacklog) {
    Bench& bench = bench_short_stall;
    bench.start();
    for (int k = 0; k < 40; ++k) {
        (void)bench.period();
    }
    bench.stall(50);
    (void)bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), messages::kBoxFaultPeriodOverrun);
    SCOPEKIN_EXPECT_TRUE(!insertion_held(bench));
    (void)bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), 0);
    SCOPEKIN_EXPECT_EQ(bench.box.counters().period_overruns, 10U);
}

// Frames lost before the box read them (the loopback queue overflowing, as a kernel socket buffer
// would): counted as dropped, kBoxFaultReceiveDropped within 3 periods, cleared once no more are
// lost; the box keeps publishing throughout.
SCOPEKIN_TEST(SensorBox, ReceiveDropsAreFlaggedWithinThreePeriodsAndClear) {
    Bench& bench = bench_dropped;
    bench.wire.box().set_filtering_supported(false);  // foreign frames must reach its queue
    bench.start();
    for (int k = 0; k < 20; ++k) {
        (void)bench.period();
    }
    bench.foreign_per_ms = 300;  // 1,510 frames a period into a 1,024-frame queue
    int flagged_after = 0;
    for (int k = 1; k <= 3 && flagged_after == 0; ++k) {
        const Published out = bench.period();
        SCOPEKIN_EXPECT_EQ(out.estimates, 1);
        if ((bench.box.box_faults() & messages::kBoxFaultReceiveDropped) != 0U) flagged_after = k;
    }
    SCOPEKIN_EXPECT_TRUE(flagged_after >= 1 && flagged_after <= 3);
    SCOPEKIN_EXPECT_TRUE(bench.box.can_counters().dropped > 0U);
    bench.foreign_per_ms = 0;
    const std::uint32_t dropped = bench.box.can_counters().dropped;
    int cleared_after = 0;
    for (int k = 1; k <= 20 && cleared_after == 0; ++k) {
        const Published out = bench.period();
        SCOPEKIN_EXPECT_EQ(out.estimates, 1);
        if (bench.box.box_faults() == 0U) cleared_after = k;
    }
    SCOPEKIN_EXPECT_TRUE(cleared_after >= 1);
    SCOPEKIN_EXPECT_TRUE(bench.box.can_counters().dropped - dropped < 1000U);  // the last ms's
}

// main's timer reports skipped periods: kBoxFaultPeriodOverrun in that period, in BoxStatus at
// once, the counter on the wire, cleared the next period.
SCOPEKIN_TEST(SensorBox, PeriodOverrunsAreFlaggedAndClear) {
    Bench& bench = bench_overrun;
    bench.start();
    for (int k = 0; k < 20; ++k) {
        (void)bench.period();
    }
    bench.overruns = 3;
    Published out = bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), messages::kBoxFaultPeriodOverrun);
    SCOPEKIN_EXPECT_EQ(out.statuses, 1);
    SCOPEKIN_EXPECT_EQ(out.status.driver_faults, messages::kBoxFaultPeriodOverrun);
    SCOPEKIN_EXPECT_EQ(out.status.period_overruns, 3U);
    out = bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.box_faults(), 0);
    SCOPEKIN_EXPECT_EQ(out.statuses, 1);
    SCOPEKIN_EXPECT_EQ(out.status.driver_faults, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.counters().period_overruns, 3U);
}

namespace {

/// The test bench's tracker as an endless byte stream: poses of sensors 0..3 and a tip force in
/// turn (32 + 32 + 32 + 32 + 17 = 145 bytes a round), device time +1 ms per frame of a source.
class TrackerStream {
public:
    /// The next `count` bytes of the stream into `out` (count <= out.size()).
    void next(std::span<std::uint8_t> out) {
        for (std::uint8_t& byte : out) {
            if (offset_ == size_) refill();
            byte = frame_[offset_++];
        }
    }
    [[nodiscard]] std::uint32_t frames_started() const { return frames_; }

private:
    void refill() {
        const std::uint32_t source = frames_ % 5U;
        const std::uint32_t time_us = 1000U * (frames_ / 5U + 1U);
        if (source < 4U) {
            protocol::EmPoseMessage pose{};
            pose.device_time_us = time_us;
            pose.sensor_id = static_cast<std::uint8_t>(source);
            pose.position_um = {1000 * static_cast<std::int32_t>(source), 2000, 3000};
            pose.orientation_q14 = {16384, 0, 0, 0};
            size_ = protocol::encode_em_pose(pose, frame_);
        } else {
            protocol::TipForceMessage force{};
            force.device_time_us = time_us;
            force.force_mN = {0, 0, 500};
            size_ = protocol::encode_tip_force(force, frame_);
        }
        offset_ = 0;
        ++frames_;
    }

    std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> frame_{};
    std::size_t size_{0};
    std::size_t offset_{0};
    std::uint32_t frames_{0};
};

/// Bytes a saturated 921,600 bit/s 8N1 line carries in `ms` milliseconds from the start:
/// 92,160 bytes/s = 92.16 bytes/ms.
std::size_t saturated_bytes(std::uint32_t ms) {
    return static_cast<std::size_t>(std::uint64_t{ms} * 9216U / 100U);
}

TrackerStream saturated_stream{};
TrackerStream no_sync_stream{};

}  // namespace

// A saturated 921,600 bit/s line: 461 bytes arrive every 5 ms period (the bench's sensors sending
// back to back).  Every byte is read in the period it arrived, nothing is lost or discarded,
// every frame becomes a valid sample, and the box raises no tracker fault.
SCOPEKIN_TEST(SensorBox, ASaturated921600BaudLineIsReadCompletelyEveryPeriod) {
    Bench& bench = bench_saturated;
    hal::LoopbackSerialPort& line = saturated_line;
    TrackerStream& stream = saturated_stream;
    bench.start(&line);
    std::array<std::uint8_t, 128> bytes{};
    std::uint32_t ms = 0;
    std::size_t offered = 0;  // bytes the line carried
    std::size_t written = 0;  // ... and the ones the box's receive buffer took
    std::uint32_t faulty_periods = 0;
    std::uint32_t periods_behind = 0;
    for (int k = 0; k < 200; ++k) {  // 1 s
        for (int m = 0; m < 5; ++m) {
            ++ms;
            const std::size_t count = saturated_bytes(ms) - offered;  // 92 or 93
            stream.next(std::span<std::uint8_t>{bytes.data(), count});
            offered += count;
            written += line.device_write(std::span<const std::uint8_t>{bytes.data(), count});
        }
        const Published out = bench.period();
        SCOPEKIN_EXPECT_EQ(out.estimates, 1);
        // Everything that arrived is read in this period.
        periods_behind += line.counters().bytes_received == written ? 0U : 1U;
        if (k > 0 && (bench.box.tracker_faults() != 0U ||
                      (bench.box.box_faults() & messages::kBoxFaultSerialFraming) != 0U)) {
            ++faulty_periods;
        }
    }
    SCOPEKIN_EXPECT_EQ(periods_behind, 0U);
    SCOPEKIN_EXPECT_EQ(offered, 92160U);  // the line's full second
    SCOPEKIN_EXPECT_EQ(written, offered);
    SCOPEKIN_EXPECT_EQ(line.counters().overruns, 0U);
    SCOPEKIN_EXPECT_EQ(faulty_periods, 0U);
    const auto counters = bench.box.em_tracker().counters();
    // Every frame but the one still arriving is complete and valid.
    SCOPEKIN_EXPECT_EQ(counters.link.frames_ok, stream.frames_started() - 1U);
    SCOPEKIN_EXPECT_EQ(counters.poses_ok + counters.tip_forces_ok, stream.frames_started() - 1U);
    SCOPEKIN_EXPECT_EQ(counters.link.bytes_discarded, 0U);
    SCOPEKIN_EXPECT_EQ(counters.samples_dropped, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().valid_mask, messages::kEmAllSources);
}

// A line that sends bytes but never a frame start (noise, a wrong baud rate): a framing fault in
// TrackerFaults and DriverFaults within 3 periods (not only the stale bit after 100 ms); the box
// keeps running; when frames come back the faults clear within 3 periods.
SCOPEKIN_TEST(SensorBox, BytesWithNoSyncAreAFramingFaultWithinThreePeriods) {
    Bench& bench = bench_no_sync;
    hal::LoopbackSerialPort& line = no_sync_line;
    TrackerStream& stream = no_sync_stream;
    bench.start(&line);
    std::array<std::uint8_t, 64> bytes{};
    auto frames_for_a_period = [&]() {
        for (int m = 0; m < 5; ++m) {  // 64 bytes a ms: a round of all five sources in 2.3 ms
            stream.next(bytes);
            (void)line.device_write(bytes);
        }
    };
    for (int k = 0; k < 20; ++k) {
        frames_for_a_period();
        (void)bench.period();
    }
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_faults(), 0U);
    // Noise: bytes 0x00..0x7F, never the sync byte 0xA5, 64 per ms.  The stream's frame in
    // progress is abandoned mid-way, as when a cable is swapped.
    std::uint32_t seed = 99;
    int flagged_after = 0;
    for (int k = 1; k <= 10; ++k) {
        for (int m = 0; m < 5; ++m) {
            for (std::uint8_t& byte : bytes) {
                seed = seed * 1664525U + 1013904223U;
                byte = static_cast<std::uint8_t>((seed >> 24U) & 0x7FU);
            }
            (void)line.device_write(bytes);
        }
        const Published out = bench.period();
        SCOPEKIN_EXPECT_EQ(out.estimates, 1);
        const bool framing = (bench.box.tracker_faults() & messages::kTrackerFaultFraming) != 0U &&
                             (bench.box.box_faults() & messages::kBoxFaultSerialFraming) != 0U;
        if (flagged_after == 0 && framing) flagged_after = k;
        if (flagged_after != 0) {
            SCOPEKIN_EXPECT_TRUE(framing);  // for as long as the noise lasts
        }
    }
    SCOPEKIN_EXPECT_TRUE(flagged_after >= 1 && flagged_after <= 3);
    SCOPEKIN_EXPECT_EQ(bench.box.em_tracker().counters().link.frames_ok,
                       bench.box.em_tracker().counters().poses_ok +
                           bench.box.em_tracker().counters().tip_forces_ok);
    // Frames again: the faults clear within 3 periods.
    int cleared_after = 0;
    for (int k = 1; k <= 3 && cleared_after == 0; ++k) {
        frames_for_a_period();
        (void)bench.period();
        if (bench.box.tracker_faults() == 0U && bench.box.box_faults() == 0U) cleared_after = k;
    }
    SCOPEKIN_EXPECT_TRUE(cleared_after >= 1 && cleared_after <= 3);
}

SCOPEKIN_TEST(SensorBox, TrackerSamplesReachTheEstimatorInput) {
    Bench& bench = bench_tracker;
    bench.start(&tracker_line);
    (void)bench.period();
    // Nothing from the tracker yet: every source stale, nothing valid, nothing fresh.
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().valid_mask, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().stale_mask, messages::kEmAllSources);
    SCOPEKIN_EXPECT_TRUE((bench.box.box_faults() & messages::kBoxFaultTrackerStale) != 0U);

    scopekin::protocol::EmPoseMessage pose{};
    pose.device_time_us = 1000;
    pose.sensor_id = 3;  // sigmoid
    pose.position_um = {12500, -2000, 30000};
    pose.orientation_q14 = {16384, 0, 0, 0};
    tracker_sends(pose, scopekin::protocol::encode_em_pose);
    scopekin::protocol::TipForceMessage force{};
    force.device_time_us = 1000;
    force.force_mN = {0, 0, 1500};
    tracker_sends(force, scopekin::protocol::encode_tip_force);
    (void)bench.period();
    const scopekin::kinetics::TrackerInputs& tracker = bench.box.tracker_inputs();
    constexpr std::uint8_t kSent = messages::kEmSourceSigmoid | messages::kEmSourceTipForce;
    SCOPEKIN_EXPECT_EQ(tracker.fresh_mask, kSent);
    SCOPEKIN_EXPECT_EQ(tracker.valid_mask, kSent);
    SCOPEKIN_EXPECT_EQ(tracker.pose[3].position_mm[0].raw(),
                       Q16_16::from_ratio(25, 2).raw());  // 12.5 mm
    SCOPEKIN_EXPECT_EQ(tracker.pose[3].position_mm[2].raw(), Q16_16::from_int(30).raw());
    SCOPEKIN_EXPECT_EQ(tracker.pose[3].receive_time_us, bench.clock.now_us());
    SCOPEKIN_EXPECT_EQ(tracker.tip_force.force_N[2].raw(),
                       Q16_16::from_ratio(3, 2).raw());  // 1.5 N

    // The next period: held, no longer fresh.
    (void)bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().fresh_mask, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().valid_mask, kSent);
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().pose[3].position_mm[0].raw(),
                       Q16_16::from_ratio(25, 2).raw());

    // A flagged sample (device status) changes nothing the estimator sees; a corrupted frame is a
    // framing fault in both of the box's fault signals.
    pose.device_time_us = 2000;
    pose.status = scopekin::protocol::kEmStatusDisconnected;
    pose.position_um = {0, 0, 0};
    tracker_sends(pose, scopekin::protocol::encode_em_pose);
    std::array<std::uint8_t, scopekin::protocol::kEmTrackerMaxFrameSize> corrupted{};
    force.device_time_us = 2000;
    const std::size_t size = scopekin::protocol::encode_tip_force(force, corrupted);
    corrupted[size - 1U] = static_cast<std::uint8_t>(corrupted[size - 1U] ^ 0xFFU);  // CRC wrong
    (void)tracker_line.device_write(std::span<const std::uint8_t>{corrupted.data(), size});
    (void)bench.period();
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().fresh_mask, 0U);
    SCOPEKIN_EXPECT_EQ(bench.box.tracker_inputs().pose[3].position_mm[0].raw(),
                       Q16_16::from_ratio(25, 2).raw());
    SCOPEKIN_EXPECT_TRUE((bench.box.tracker_faults() & messages::kTrackerFaultDeviceStatus) != 0U);
    SCOPEKIN_EXPECT_TRUE((bench.box.tracker_faults() & messages::kTrackerFaultFraming) != 0U);
    SCOPEKIN_EXPECT_TRUE((bench.box.box_faults() & messages::kBoxFaultSerialFraming) != 0U);
}

// The one place the EM tracker's and the estimator's flags become the wire's fault bits.
SCOPEKIN_TEST(BoxFaults, MappingsFollowTheDbc) {
    using namespace scopekin::messages;
    // TrackerFaults: bits 0..5 are the sample checks, 6 framing, 7 the link.
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultStale), kTrackerFaultStale);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultTimestamp), kTrackerFaultDeviceTime);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultDeviceStatus), kTrackerFaultDeviceStatus);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultBadChecksum), kTrackerFaultFraming);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultBufferOverflow), kTrackerFaultFraming);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultNoSync), kTrackerFaultFraming);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultSerial), kTrackerFaultLink);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultQueueOverflow), kTrackerFaultLink);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(0xFFFU), 0xFFU);
    // DriverFaults: framing and staleness of the tracker; its sample checks are not the box's.
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultUnknownType), kBoxFaultSerialFraming);
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultNoSync), kBoxFaultSerialFraming);
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultStale), kBoxFaultTrackerStale);
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultOutOfRange | kEmFaultSerial), 0U);
    // KineticEstimate: InputsStale for a held handle signal, DepthClamped for a limited depth.
    SCOPEKIN_EXPECT_TRUE(inputs_stale(scopekin::kinetics::kFaultRollStale));
    SCOPEKIN_EXPECT_TRUE(!inputs_stale(scopekin::kinetics::kFaultForceRange));
    SCOPEKIN_EXPECT_TRUE(depth_clamped(scopekin::kinetics::kFaultInsertionJump));
    SCOPEKIN_EXPECT_TRUE(!depth_clamped(scopekin::kinetics::kFaultInsertionStale));
}
