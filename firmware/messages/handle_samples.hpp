// handle_samples.hpp — what the handle-sensor driver publishes: one plain, time-stamped sample
// per sensor (force/torque cell 0x110, insertion/roll encoder 0x111), and the period's view of
// both: the latest valid sample of each and whether a new one arrived this period.
//
// Plain structs, the seam between drivers, the executive and the simulator (the PX4 uORB idea):
// drivers fill them, the executive assembles kinetics::Inputs from them (executive/
// estimator_inputs.hpp).  Q16.16 throughout (firmware/fixed_point/RANGES.md); times are the box's
// clock (the CAN backend's receive time stamps), µs.
#pragma once

#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::messages {

using fixed_point::Q16_16;

/// One valid frame of the force/torque cell.
struct ForceTorqueSample {
    Q16_16 force_N{};     ///< axial force at the handle, + pushing in
    Q16_16 torque_Nmm{};  ///< torque about the shaft axis
    std::uint64_t receive_time_us{0};
};

/// One valid frame of the insertion/roll encoder.
struct InsertionRollSample {
    Q16_16 insertion_mm{};  ///< scope length past the anus
    Q16_16 roll_rad{};      ///< shaft roll, unwrapped
    std::uint64_t receive_time_us{0};
};

/// The handle sensors as one period sees them: the held (latest valid) sample of each sensor —
/// all zero before its first — and whether it is fresh: new since the last period and received
/// at most one period before this one (drivers/handle_sensors.hpp: a sample read late from a
/// backlog is held, not fresh).
struct HandleSamples {
    ForceTorqueSample force_torque{};
    InsertionRollSample insertion_roll{};
    bool force_torque_fresh{false};
    bool insertion_roll_fresh{false};
};

}  // namespace scopekin::messages
