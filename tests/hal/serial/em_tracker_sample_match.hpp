// em_tracker_sample_match.hpp — does a driver sample carry exactly what a wire message said?
//
// Test support (every preset): an independent reference of the driver's µm / mN -> Q16.16
// conversion (plain int64 arithmetic, not the Q16_16 type the driver uses) and field-by-field
// comparisons of EmPoseSample / TipForceSample with the message that was sent.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/em_tracker_driver.hpp"
#include "em_tracker_stream.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::test {

/// round(value * 2^16 / 1000), half away from zero: thousandths (µm, mN) -> Q16.16 raw (mm, N).
inline std::int32_t thousandths_to_q16_raw(std::int32_t value) {
    const std::int64_t scaled = std::int64_t{value} * 65536;
    const std::int64_t magnitude = scaled < 0 ? -scaled : scaled;
    const std::int64_t rounded = (magnitude + 500) / 1000;
    return static_cast<std::int32_t>(scaled < 0 ? -rounded : rounded);
}

inline bool pose_matches(const messages::EmPoseSample& sample,
                         const protocol::EmPoseMessage& message) {
    bool same = sample.sensor_id == message.sensor_id &&
                sample.device_time_us == message.device_time_us &&
                sample.device_status == message.status;
    for (std::size_t i = 0; i < 3U; ++i) {
        same =
            same && sample.position_mm[i].raw() == thousandths_to_q16_raw(message.position_um[i]);
    }
    for (std::size_t i = 0; i < 4U; ++i) {
        // Q2.14 -> Q16.16 is exact: raw * 4.
        same = same && sample.orientation[i].raw() == std::int32_t{message.orientation_q14[i]} * 4;
    }
    return same;
}

inline bool tip_force_matches(const messages::TipForceSample& sample,
                              const protocol::TipForceMessage& message) {
    bool same =
        sample.device_time_us == message.device_time_us && sample.device_status == message.status;
    for (std::size_t i = 0; i < 3U; ++i) {
        same = same && sample.force_N[i].raw() == thousandths_to_q16_raw(message.force_mN[i]);
    }
    return same;
}

/// A valid sample (no fault flag) of the right kind that carries exactly `expected`.
inline bool sample_matches(const messages::EmTrackerSample& sample,
                           const ExpectedEmMessage& expected) {
    if (expected.type == protocol::EmTrackerMessageType::pose) {
        return sample.kind == messages::EmTrackerSampleKind::pose &&
               sample.pose.fault_flags == 0U && pose_matches(sample.pose, expected.pose);
    }
    return sample.kind == messages::EmTrackerSampleKind::tip_force &&
           sample.tip_force.fault_flags == 0U &&
           tip_force_matches(sample.tip_force, expected.tip_force);
}

}  // namespace scopekin::test
