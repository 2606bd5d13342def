// The box's cyclic executive (firmware/executive/sensor_box) on the loopback HAL, driven by
// simulated time: what it publishes every period, a sensor that stops and returns, error
// frames and bus-off, garbage on the bus that must change nothing but counters, and the test
// bench's EM tracker samples reaching the estimator's input.
#include <array>
#include <cstddef>
#include <cstdint>
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

/// What the world saw the box publish in one period.
struct Published {
    int estimates{0};
    int summaries{0};
    int alarms{0};
    int statuses{0};
    int counters{0};
    int stations{0};
    int other{0};
    protocol::KineticEstimate estimate{};
    protocol::Alarms alarm{};
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
    }

    /// One period: 5 ms of the world, then the box's period; returns what it published.
    Published period() {
        for (int ms = 0; ms < 5; ++ms) {
            world_millisecond();
        }
        box.run_period(clock.now_us(), 0);
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
Bench bench_tracker;
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
        SCOPEKIN_EXPECT_EQ(out.other, 0);
        SCOPEKIN_EXPECT_TRUE(out.estimate.estimate_valid);
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

// "Never an alarm raised or cleared because of garbage": two boxes see the same handle frames,
// one of them also a stream of garbage; every output of every period must be identical, and the
// garbage counted.
SCOPEKIN_TEST(SensorBox, GarbageChangesNothingButCounters) {
    Bench& clean = bench_clean;
    Bench& noisy = bench_noisy;
    clean.start();
    noisy.start();
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
        }
        const Published a = clean.period();
        const Published b = noisy.period();
        const auto& oa = clean.box.outputs();
        const auto& ob = noisy.box.outputs();
        SCOPEKIN_EXPECT_EQ(oa.tip_path_mm.raw(), ob.tip_path_mm.raw());
        SCOPEKIN_EXPECT_EQ(oa.max_contact_force_N.raw(), ob.max_contact_force_N.raw());
        SCOPEKIN_EXPECT_EQ(oa.self_lock_alarm, ob.self_lock_alarm);
        SCOPEKIN_EXPECT_TRUE(oa.contact_force_level == ob.contact_force_level);
        SCOPEKIN_EXPECT_EQ(oa.fault_flags, ob.fault_flags);
        SCOPEKIN_EXPECT_EQ(a.alarm.self_lock, b.alarm.self_lock);
        SCOPEKIN_EXPECT_EQ(a.alarm.contact_force_level, b.alarm.contact_force_level);
    }
    SCOPEKIN_EXPECT_EQ(noisy.box.counters().unknown_ids, garbage_unknown);
    SCOPEKIN_EXPECT_EQ(noisy.box.handle_sensors().counters().bad_length, garbage_bad_length);
    SCOPEKIN_EXPECT_EQ(noisy.box.handle_sensors().counters().counter_gaps, 0U);
    SCOPEKIN_EXPECT_TRUE((noisy.box.box_faults() &
                          (messages::kBoxFaultUnknownId | messages::kBoxFaultBadLength)) != 0U);
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
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultSerial), kTrackerFaultLink);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(kEmFaultQueueOverflow), kTrackerFaultLink);
    SCOPEKIN_EXPECT_EQ(tracker_faults_of(0xFFFU), 0xFFU);
    // DriverFaults: framing and staleness of the tracker; its sample checks are not the box's.
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultUnknownType), kBoxFaultSerialFraming);
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultStale), kBoxFaultTrackerStale);
    SCOPEKIN_EXPECT_EQ(box_faults_of_tracker(kEmFaultOutOfRange | kEmFaultSerial), 0U);
    // KineticEstimate: InputsStale for a held handle signal, DepthClamped for a limited depth.
    SCOPEKIN_EXPECT_TRUE(inputs_stale(scopekin::kinetics::kFaultRollStale));
    SCOPEKIN_EXPECT_TRUE(!inputs_stale(scopekin::kinetics::kFaultForceRange));
    SCOPEKIN_EXPECT_TRUE(depth_clamped(scopekin::kinetics::kFaultInsertionJump));
    SCOPEKIN_EXPECT_TRUE(!depth_clamped(scopekin::kinetics::kFaultInsertionStale));
}
