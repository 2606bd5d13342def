// estimator_inputs.cpp — see estimator_inputs.hpp.
#include "executive/estimator_inputs.hpp"

namespace scopekin::executive {

void keep_tracker_sample(const messages::EmTrackerSample& sample,
                         kinetics::TrackerInputs& tracker) {
    std::uint8_t source_bit = 0;
    if (sample.kind == messages::EmTrackerSampleKind::tip_force) {
        if (sample.tip_force.fault_flags != 0U) return;
        tracker.tip_force = sample.tip_force;
        source_bit = messages::kEmSourceTipForce;
    } else {
        // A valid pose has a known sensor id (kEmFaultUnknownSensor otherwise).
        if (sample.pose.fault_flags != 0U || sample.pose.sensor_id >= messages::kEmSensorCount)
            return;
        tracker.pose[sample.pose.sensor_id] = sample.pose;
        source_bit = static_cast<std::uint8_t>(1U << sample.pose.sensor_id);
    }
    tracker.fresh_mask = static_cast<std::uint8_t>(tracker.fresh_mask | source_bit);
    tracker.valid_mask = static_cast<std::uint8_t>(tracker.valid_mask | source_bit);
}

kinetics::Inputs assemble_inputs(const messages::HandleSamples& handle,
                                 const kinetics::TrackerInputs& tracker) {
    kinetics::Inputs inputs{};
    inputs.handle_force_N = handle.force_torque.force_N;
    inputs.handle_torque_Nmm = handle.force_torque.torque_Nmm;
    inputs.insertion_mm = handle.insertion_roll.insertion_mm;
    inputs.roll_rad = handle.insertion_roll.roll_rad;
    if (handle.force_torque_fresh) {
        inputs.fresh_mask |= kinetics::kHandleForce | kinetics::kHandleTorque;
    }
    if (handle.insertion_roll_fresh) {
        inputs.fresh_mask |= kinetics::kInsertion | kinetics::kRoll;
    }
    inputs.tracker = tracker;
    return inputs;
}

}  // namespace scopekin::executive
