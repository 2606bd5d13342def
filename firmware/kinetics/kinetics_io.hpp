// kinetics_io.hpp — what goes into and comes out of one step of the firmware's kinetics.
//
// Plain structs (the seam between drivers, the kinetic model, the monitors and the simulator:
// PX4-uORB style), all fixed point, all fixed size.  Units are in the names.
//
// Fixed-point formats (range analysis: firmware/fixed_point/RANGES.md):
//   every Q16_16 field below is Q16.16 (int32 raw, 2^-16 resolution, ±32768 range).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"
#include "messages/em_tracker_samples.hpp"

namespace scopekin::kinetics {

using fixed_point::Q16_16;

/// Contact stations of the reduced model: points on the scope at fixed distances from the tip
/// (station 0 = the tip).  Compile-time capacity; the generated tables fix the spacing.
inline constexpr std::size_t kStationCapacity = 12;
/// Distal stations whose stick state feeds the self-lock monitor (tip and the next ones).
inline constexpr std::size_t kDistalStations = 3;

/// Handle sensor signals, one bit each in Inputs::fresh_mask.
enum InputSignal : std::uint8_t {
    kHandleForce = 1U << 0U,
    kHandleTorque = 1U << 1U,
    kInsertion = 1U << 2U,
    kRoll = 1U << 3U,
};
inline constexpr std::uint8_t kAllInputSignals = kHandleForce | kHandleTorque | kInsertion | kRoll;

/// The test bench's optional serial sensors (EM tracker, tip force), as the executive last
/// received them: the latest valid sample of each source.  Without a serial port every sample
/// is zero, never fresh, never valid.  The estimator reads the tip's and the sigmoid's poses
/// (tip_odometer.hpp, slack_excess.hpp); the tip force is validated and held, not read.
struct TrackerInputs {
    std::array<messages::EmPoseSample, messages::kEmSensorCount> pose{};  ///< by EmSensor
    messages::TipForceSample tip_force{};
    std::uint8_t fresh_mask{0};  ///< messages::EmTrackerSource bits: new valid sample this period
    std::uint8_t valid_mask{0};  ///< ... a valid sample since start
    std::uint8_t stale_mask{0};  ///< ... the driver flags stale now
};

/// One period's sensor samples (the executive assembles them from the drivers' messages:
/// executive/estimator_inputs.hpp).
struct Inputs {
    Q16_16 handle_force_N{};     ///< axial force at the handle, + pushing in
    Q16_16 handle_torque_Nmm{};  ///< torque about the shaft axis
    Q16_16 insertion_mm{};       ///< scope length past the anus
    Q16_16 roll_rad{};           ///< shaft roll, unwrapped
    std::uint8_t fresh_mask{0};  ///< InputSignal bits: a new, valid sample arrived this period
    TrackerInputs tracker{};     ///< test bench only (optional)
};

/// Fault flags (Outputs::fault_flags, bit set = fault present this step).
enum FaultFlag : std::uint32_t {
    kFaultInsertionStale = 1U << 0U,  ///< no fresh insertion sample: depth held
    kFaultInsertionRange = 1U << 1U,  ///< insertion outside the model's range: saturated
    kFaultInsertionJump = 1U << 2U,   ///< insertion moved faster than a hand can: limited
    kFaultForceStale = 1U << 3U,
    kFaultForceRange = 1U << 4U,
    kFaultTorqueStale = 1U << 5U,
    kFaultTorqueRange = 1U << 6U,
    kFaultRollStale = 1U << 7U,
    kFaultRollRange = 1U << 8U,
    kFaultContactResidual = 1U << 9U,  ///< the contact solve left a residual above its bound
    kFaultSaturation = 1U << 10U,      ///< an internal quantity hit its fixed-point limit
    /// Depth outside the reduced model's travel run in use (default 20..1692 mm): the model (its
    /// stations, forces and monitors) is clamped to it; the published tip (the regressor's) is not.
    kFaultDepthOutsideModel = 1U << 11U,
    kFaultConfig = 1U << 12U,        ///< init refused the configuration: no estimate
    kFaultMonitorInput = 1U << 13U,  ///< a monitor rejected its input (held its output)
    /// The force cell has been stale for Config::force_blind_after_steps periods in a row or more:
    /// the handle force is lost, the estimate runs on the depth and the force history up to the
    /// cell's last valid reading (kinetics.hpp, "A stale force cell") until it returns.
    kFaultForceBlind = 1U << 14U,
};
/// Every FaultFlag bit (a new flag moves this to its own bit; checks reject any bit beyond).
inline constexpr std::uint32_t kAllFaultFlags = (kFaultForceBlind << 1U) - 1U;

/// Contact state of a station (mirrors contact::ContactState).
enum class StationState : std::uint8_t {
    separated,
    sticking,
    slipping,
    degenerate
};

struct StationEstimate {
    Q16_16 arc_from_tip_mm{};     ///< where on the scope
    Q16_16 path_position_mm{};    ///< where along the colon centerline (from the anus)
    Q16_16 normal_force_N{};      ///< >= 0
    Q16_16 tangential_force_N{};  ///< |f_T| >= 0
    StationState state{StationState::separated};
};

enum class ContactForceLevel : std::uint8_t {
    normal,
    warning,
    critical
};

struct Outputs {
    std::uint32_t step_index{0};
    /// Tip position along the colon centerline: the reduced model's while the handle's evidence
    /// trusts it (tip_from_model), else depth - the slack regressor's slack (slack_regressor.hpp),
    /// or the tip observer's when no regressor is configured; that, fused with the bench's EM
    /// tracker's tip odometry while the tracker is connected (tip_from_tracker, tip_odometer.hpp).
    Q16_16 tip_path_mm{};
    Q16_16 tip_uncertainty_mm{};     ///< one standard deviation of tip_path_mm
    Q16_16 tip_velocity_mm_per_s{};  ///< d/dt of tip_path_mm
    Q16_16 model_tip_path_mm{};      ///< the reduced model's tip (what the monitors read)
    /// The handle's evidence that this patient is the model's training patient (model_evidence.hpp)
    Q16_16 model_log_likelihood_ratio{};
    bool tip_from_model{false};     ///< the published tip is the model's (the evidence trusts it)
    bool tip_from_tracker{false};   ///< ... fused with the bench's EM tracker (tip_odometer.hpp)
    Q16_16 observer_tip_path_mm{};  ///< the tip observer's own tip (an input of the regressor)
    Q16_16 advance_efficiency{};    ///< tip advance / handle advance over the window (0..1+)
    std::array<StationEstimate, kStationCapacity> stations{};
    std::uint8_t active_stations{0};  ///< stations inside the colon this step
    /// The largest contact force: the reduced model's (largest |f| over the stations) while the
    /// handle's evidence trusts the model, else the force trees' regression on the handle's
    /// history (Config::contact_force_trees; >= 0); the station and path are the model's.
    Q16_16 max_contact_force_N{};
    Q16_16 max_contact_force_uncertainty_N{};  ///< one SD of max_contact_force_N
    Q16_16 model_max_contact_force_N{};        ///< the reduced model's largest |f| over stations
    std::uint8_t max_contact_station{0};
    Q16_16 max_contact_path_mm{};     ///< where along the colon
    std::uint8_t distal_sticking{0};  ///< distal stations (< kDistalStations) in stick
    /// The loop / self-lock alarm: the reduced model's self-lock monitor while the handle's evidence
    /// trusts the model, else the loop alarm from evidence (Config::loop_alarm_trees).
    bool self_lock_alarm{false};
    bool model_self_lock_alarm{false};  ///< the reduced model's self-lock monitor
    Q16_16 loop_score{};  ///< the loop alarm's score (0 without its trees; evidence_alarm.hpp)
    /// The contact-force level on the published largest force (max_contact_force_N).
    ContactForceLevel contact_force_level{ContactForceLevel::normal};
    /// The same monitor on the reduced model's largest force (model_max_contact_force_N).
    ContactForceLevel model_contact_force_level{ContactForceLevel::normal};
    std::uint32_t fault_flags{0};
};

}  // namespace scopekin::kinetics
