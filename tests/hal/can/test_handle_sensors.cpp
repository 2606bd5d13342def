// The handle sensors' CAN driver (firmware/drivers/handle_sensors): time-stamped samples,
// freshness, staleness, and every fault counted (as the box's fault bits) without touching the
// held sample.
#include <cstdint>

#include "drivers/handle_sensors.hpp"
#include "portable_check.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
namespace protocol = scopekin::protocol;
namespace drivers = scopekin::drivers;
namespace messages = scopekin::messages;
using scopekin::hal::ReceivedCanFrame;

ReceivedCanFrame force_frame(std::int32_t force_N, std::uint8_t counter, std::uint64_t time_us,
                             std::uint8_t status = 0) {
    protocol::HandleForceTorque message{};
    message.force_N = Q16_16::from_int(force_N);
    message.counter = counter;
    message.status = status;
    return ReceivedCanFrame{protocol::encode(message), time_us};
}

ReceivedCanFrame insertion_frame(std::int32_t insertion_mm, std::uint8_t counter,
                                 std::uint64_t time_us) {
    protocol::InsertionRoll message{};
    message.insertion_mm = Q16_16::from_int(insertion_mm);
    message.counter = counter;
    return ReceivedCanFrame{protocol::encode(message), time_us};
}

}  // namespace

SCOPEKIN_TEST(HandleSensors, ValidSamplesAreFreshOncePerPeriod) {
    drivers::HandleSensors sensors{};
    SCOPEKIN_EXPECT_TRUE(sensors.accept(force_frame(3, 0, 1000)));
    SCOPEKIN_EXPECT_TRUE(sensors.accept(force_frame(4, 1, 2000)));
    SCOPEKIN_EXPECT_TRUE(sensors.accept(insertion_frame(250, 7, 2000)));
    messages::HandleSamples samples = sensors.take_samples(5000);
    SCOPEKIN_EXPECT_TRUE(samples.force_torque_fresh && samples.insertion_roll_fresh);
    SCOPEKIN_EXPECT_EQ(samples.force_torque.force_N.raw(),
                       Q16_16::from_int(4).raw());                    // the latest
    SCOPEKIN_EXPECT_EQ(samples.force_torque.receive_time_us, 2000U);  // ... with its receive time
    SCOPEKIN_EXPECT_EQ(samples.insertion_roll.insertion_mm.raw(), Q16_16::from_int(250).raw());
    SCOPEKIN_EXPECT_EQ(samples.insertion_roll.receive_time_us, 2000U);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    // Nothing new: the values are held, nothing is fresh, not yet stale (5 ms < 15 ms).
    samples = sensors.take_samples(10000);
    SCOPEKIN_EXPECT_TRUE(!samples.force_torque_fresh && !samples.insertion_roll_fresh);
    SCOPEKIN_EXPECT_EQ(samples.force_torque.force_N.raw(), Q16_16::from_int(4).raw());
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    SCOPEKIN_EXPECT_EQ(sensors.counters().force_torque_samples, 2U);
}

SCOPEKIN_TEST(HandleSensors, StaleAfterTheTimeoutAndRecovers) {
    // Periods up to 12 ms apart here: samples up to 15 ms old count as fresh (not late).
    drivers::HandleSensors sensors{drivers::HandleSensorConfig{15000, 15000}};
    // Never seen: stale from the start.
    (void)sensors.take_samples(1000);
    SCOPEKIN_EXPECT_EQ(sensors.faults(),
                       messages::kBoxFaultForceTorqueStale | messages::kBoxFaultEncoderStale);
    (void)sensors.accept(force_frame(1, 0, 2000));
    (void)sensors.accept(insertion_frame(100, 0, 2000));
    (void)sensors.take_samples(5000);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    (void)sensors.accept(insertion_frame(101, 1, 6000));
    (void)sensors.take_samples(17000);  // force: 15 ms old, not beyond the timeout
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    (void)sensors.take_samples(17001);  // 15.001 ms: stale; insertion (11 ms) not
    SCOPEKIN_EXPECT_EQ(sensors.faults(), messages::kBoxFaultForceTorqueStale);
    SCOPEKIN_EXPECT_EQ(sensors.counters().stale_events, 1U);  // never-seen is stale, not an event
    (void)sensors.accept(force_frame(2, 9, 18000));  // counter jumped while stale: not a gap
    const messages::HandleSamples samples = sensors.take_samples(20000);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    SCOPEKIN_EXPECT_EQ(samples.force_torque.force_N.raw(), Q16_16::from_int(2).raw());
    SCOPEKIN_EXPECT_EQ(sensors.counters().counter_gaps, 0U);
}

SCOPEKIN_TEST(HandleSensors, FaultsAreCountedAndTheHeldSampleKept) {
    drivers::HandleSensors sensors{};
    (void)sensors.accept(force_frame(5, 0, 1000));
    // Counter gap: 0 -> 3 means frames 1 and 2 were lost (2 counted); the sample is used.
    (void)sensors.accept(force_frame(6, 3, 2000));
    // Wrong length.
    ReceivedCanFrame short_frame = force_frame(50, 4, 3000);
    short_frame.frame.length = 4;
    SCOPEKIN_EXPECT_TRUE(sensors.accept(short_frame));
    // The cell reports overload: not valid.
    (void)sensors.accept(force_frame(60, 4, 4000, 0x01));
    // Not the driver's: another id, an error frame, an extended frame.
    ReceivedCanFrame other = force_frame(70, 5, 4000);
    other.frame.id = 0x123;
    SCOPEKIN_EXPECT_TRUE(!sensors.accept(other));
    ReceivedCanFrame extended = force_frame(70, 5, 4000);
    extended.frame.extended = true;
    SCOPEKIN_EXPECT_TRUE(!sensors.accept(extended));

    const messages::HandleSamples samples = sensors.take_samples(5000);
    SCOPEKIN_EXPECT_EQ(samples.force_torque.force_N.raw(), Q16_16::from_int(6).raw());
    SCOPEKIN_EXPECT_EQ(sensors.counters().counter_gaps, 2U);
    SCOPEKIN_EXPECT_EQ(sensors.counters().bad_length, 1U);
    SCOPEKIN_EXPECT_EQ(sensors.counters().sensor_status, 1U);
    SCOPEKIN_EXPECT_EQ(sensors.counters().force_torque_samples, 2U);
    SCOPEKIN_EXPECT_EQ(sensors.faults(),
                       messages::kBoxFaultCounterGap | messages::kBoxFaultBadLength |
                           messages::kBoxFaultSensorStatus | messages::kBoxFaultEncoderStale);
    // The flags belong to the period they happened in.
    (void)sensors.accept(force_frame(7, 5, 6000));
    (void)sensors.take_samples(10000);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), messages::kBoxFaultEncoderStale);
}

// A sample is fresh only if it is new AND received at most max_sample_age_us (one period)
// before the period: one read late from a backlog is held, counted and flagged.
SCOPEKIN_TEST(HandleSensors, ASampleOlderThanAPeriodIsNotFresh) {
    drivers::HandleSensors sensors{drivers::HandleSensorConfig{15000, 5000}};
    (void)sensors.accept(force_frame(1, 0, 4000));
    (void)sensors.accept(insertion_frame(100, 0, 4000));
    messages::HandleSamples samples = sensors.take_samples(5000);
    SCOPEKIN_EXPECT_TRUE(samples.force_torque_fresh && samples.insertion_roll_fresh);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    // The next period reads samples of 4.999 ms and 5.001 ms before it: the first is fresh, the
    // second (read late, as from a backlog) is held: not fresh, counted, flagged.
    (void)sensors.accept(force_frame(2, 1, 5001));
    (void)sensors.accept(insertion_frame(101, 1, 4999));
    samples = sensors.take_samples(10000);
    SCOPEKIN_EXPECT_TRUE(samples.force_torque_fresh);
    SCOPEKIN_EXPECT_TRUE(!samples.insertion_roll_fresh);
    SCOPEKIN_EXPECT_EQ(samples.insertion_roll.insertion_mm.raw(), Q16_16::from_int(101).raw());
    SCOPEKIN_EXPECT_EQ(sensors.counters().late_samples, 1U);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), messages::kBoxFaultReceiveBacklog);  // not yet stale
    // A timely sample again: fresh, the flag gone.
    (void)sensors.accept(insertion_frame(102, 2, 14000));
    samples = sensors.take_samples(15000);
    SCOPEKIN_EXPECT_TRUE(samples.insertion_roll_fresh);
    SCOPEKIN_EXPECT_EQ(sensors.faults(), 0);
    SCOPEKIN_EXPECT_EQ(sensors.counters().late_samples, 1U);
}

SCOPEKIN_TEST(HandleSensors, ItsReceiveFiltersPassExactlyItsFrames) {
    scopekin::hal::CanReceiveFilter filter{};
    SCOPEKIN_EXPECT_TRUE(filter.assign(drivers::kHandleSensorReceiveFilters));
    SCOPEKIN_EXPECT_TRUE(filter.passes(force_frame(1, 0, 0).frame));
    SCOPEKIN_EXPECT_TRUE(filter.passes(insertion_frame(1, 0, 0).frame));
    ReceivedCanFrame other = force_frame(1, 0, 0);
    for (std::uint32_t id = 0; id <= scopekin::hal::kCanStandardIdMask; ++id) {  // bound: 2048
        other.frame.id = id;
        const bool handle =
            id == protocol::kHandleForceTorqueId || id == protocol::kInsertionRollId;
        SCOPEKIN_EXPECT_EQ(filter.passes(other.frame), handle);
    }
    other.frame.id = protocol::kHandleForceTorqueId;
    other.frame.extended = true;  // the same number as a 29-bit id
    SCOPEKIN_EXPECT_TRUE(!filter.passes(other.frame));
    other.frame.extended = false;
    other.frame.remote = true;  // a remote request for it
    SCOPEKIN_EXPECT_TRUE(!filter.passes(other.frame));
    scopekin::hal::CanFrame error{};
    error.error = true;
    error.id = scopekin::hal::kCanErrorBusOff;
    SCOPEKIN_EXPECT_TRUE(filter.passes(error));  // the controller's reports always pass
}
