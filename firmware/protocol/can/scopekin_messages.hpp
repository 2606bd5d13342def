// scopekin_messages.hpp — the sensor box's CAN messages: identifiers, signal layouts and typed
// encoders/decoders.  The single source of truth is firmware/protocol/scopekin.dbc; the layouts
// below are checked against it signal by signal, and every encoder and decoder against
// python3-canmatrix's reading of it, by tests/hal/can/check_dbc.py.
//
// Classic CAN, 11-bit identifiers, little-endian signals.  Physical values are Q16.16 (units in
// the field names); scaling and overflow: can_signal.hpp.
//
// Decoding is strict: the identifier must be the message's, the frame a standard data frame
// (not extended, remote or error), the length exactly the DBC's, and enumerations within their
// defined values.  Anything else is refused with the reason (DecodeResult) and the output is left
// untouched, so the caller counts it and keeps its last valid sample.
// Encoding saturates each value to its signal's range (the DBC's [min|max]).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "fixed_point/q_format.hpp"
#include "hal/can_bus.hpp"
#include "protocol/can/can_signal.hpp"

namespace scopekin::protocol {

using fixed_point::Q16_16;

// ---- identifiers (11-bit) ---------------------------------------------------------------------
inline constexpr std::uint32_t kHandleForceTorqueId = 0x110;
inline constexpr std::uint32_t kInsertionRollId = 0x111;
inline constexpr std::uint32_t kBoxStatusId = 0x180;
inline constexpr std::uint32_t kKineticEstimateId = 0x181;
inline constexpr std::uint32_t kContactSummaryId = 0x182;
inline constexpr std::uint32_t kAlarmsId = 0x183;
inline constexpr std::uint32_t kBoxCountersId = 0x184;
inline constexpr std::uint32_t kEstimateEvidenceId = 0x185;
inline constexpr std::uint32_t kStationForcesId = 0x190;

// ---- inputs: handle sensors -------------------------------------------------------------------

/// 0x110, 1 kHz.  CellStatus bits: 0 overload, 1 sensor fault, 2 not zeroed.
struct HandleForceTorque {
    Q16_16 force_N{};     ///< axial, + pushing in; 0.005 N resolution
    Q16_16 torque_Nmm{};  ///< about the shaft axis; 0.1 N·mm resolution
    std::uint8_t status{0};
    std::uint8_t counter{0};  ///< 0..15, +1 per frame
};

/// 0x111, 1 kHz.  EncoderStatus bits: 0 encoder fault, 1 not referenced.
struct InsertionRoll {
    Q16_16 insertion_mm{};    ///< 0.01 mm resolution; the signal spans ±83 m, Q16.16 only ±32 m
    Q16_16 roll_rad{};        ///< unwrapped; 0.0001 rad resolution
    std::uint8_t status{0};   ///< 0..15
    std::uint8_t counter{0};  ///< 0..15
};

// ---- outputs: the box -------------------------------------------------------------------------

enum class BoxState : std::uint8_t {
    starting = 0,
    running = 1,
    degraded = 2,
    no_estimate = 3
};
enum class CanState : std::uint8_t {
    error_active = 0,
    warning = 1,
    error_passive = 2,
    bus_off = 3
};

/// 0x180: every 20 periods and at once when a fault bit changes.
struct BoxStatus {
    std::uint8_t heartbeat{0};
    BoxState state{BoxState::starting};
    CanState can_state{CanState::error_active};
    std::uint16_t kinetic_faults{0};  ///< kinetics::FaultFlag bits
    std::uint16_t driver_faults{0};   ///< messages::BoxFault bits
    std::uint8_t period_overruns{0};  ///< saturating
    std::uint8_t tracker_faults{0};
};

/// 0x181: every period.
struct KineticEstimate {
    Q16_16 tip_path_mm{};            ///< 0.1 mm
    Q16_16 tip_velocity_mm_per_s{};  ///< 0.1 mm/s
    Q16_16 advance_efficiency{};     ///< 0.001
    bool estimate_valid{false};
    bool inputs_stale{false};
    bool depth_clamped{false};
    Q16_16 tip_uncertainty_mm{};  ///< 10 mm, 0..310 (saturates): one SD of tip_path_mm (1.1)
    std::uint8_t step_counter{0};
};

/// 0x182: every period.
struct ContactSummary {
    Q16_16 max_contact_force_N{};         ///< 0.001 N, 0..65.535 N
    Q16_16 max_contact_path_mm{};         ///< 0.1 mm, 0..6553.5 mm
    std::uint8_t max_contact_station{0};  ///< 0..15
    std::uint8_t active_stations{0};      ///< 0..15
    std::uint8_t distal_sticking{0};      ///< 0..15
    std::uint16_t sticking_mask{0};       ///< 12 bits: bit k = station k sticks
    std::uint8_t step_counter{0};
};

/// 0x183: every period.
struct Alarms {
    bool self_lock{false};
    std::uint8_t contact_force_level{0};  ///< 0 normal, 1 warning, 2 critical
    bool valid{false};
    bool tip_from_model{false};        ///< KineticEstimate's tip is the reduced model's (1.2)
    std::uint8_t self_lock_raised{0};  ///< wraps
    std::uint8_t critical_raised{0};   ///< wraps
    std::uint8_t step_counter{0};
};

/// 0x184: one counter per period, round robin.  Indices: the VAL_ table of CounterIndex.
enum class BoxCounterIndex : std::uint8_t {
    can_received = 0,
    can_dropped = 1,
    can_error_frames = 2,
    can_bus_off = 3,
    can_send_failures = 4,
    bad_length = 5,
    unknown_id = 6,
    out_of_range = 7,
    counter_gaps = 8,
    stale_events = 9,
    serial_frames = 10,
    serial_bad_frames = 11,
    serial_bytes_discarded = 12,
    period_overruns = 13,
    steps = 14,
    sensor_status = 15,
    receive_backlog = 16,  ///< periods with BoxFault kBoxFaultReceiveBacklog
};
inline constexpr std::uint8_t kBoxCounterCount = 17;

struct BoxCounter {
    BoxCounterIndex index{BoxCounterIndex::can_received};
    std::uint32_t value{0};
};

/// 0x185: every period (1.3): how sure the estimate is and what the reduced model says.
struct EstimateEvidence {
    Q16_16 max_contact_force_uncertainty_N{};  ///< 0.001 N, 0..65.535 N: one SD of MaxContactForce
    Q16_16 loop_score{};                       ///< 0.0001, 0..6.5535 (the score is 0..1)
    Q16_16 model_log_likelihood_ratio{};       ///< 0.01, ±327.68 (the estimator's is in ±20)
    bool model_self_lock{false};               ///< the reduced model's self-lock monitor
    bool tip_from_tracker{false};              ///< the bench's EM tracker is fused into the tip
    std::uint8_t step_counter{0};
};

/// 0x190: one contact station per period, round robin over the active stations.
struct StationForces {
    std::uint8_t station{0};      ///< 0..15 (0 = tip)
    std::uint8_t state{0};        ///< 0 separated, 1 sticking, 2 slipping, 3 degenerate
    Q16_16 normal_force_N{};      ///< 0.001 N
    Q16_16 tangential_force_N{};  ///< 0.001 N
    Q16_16 path_mm{};             ///< 0.1 mm
    Q16_16 arc_from_tip_mm{};     ///< 5 mm
};

// ---- layouts (as in scopekin.dbc) --------------------------------------------------------------

struct MessageLayout {
    const char* name;
    std::uint32_t id;
    std::uint8_t length;
    std::span<const CanSignal> signals;
};

/// Every message of the protocol, in identifier order (for the DBC check and diagnostics).
[[nodiscard]] std::span<const MessageLayout> message_layouts();
/// The layout of message `id`, or nullptr.
[[nodiscard]] const MessageLayout* find_message_layout(std::uint32_t id);

// ---- codecs -----------------------------------------------------------------------------------

enum class DecodeResult : std::uint8_t {
    ok,
    wrong_id,      ///< not this message (standard data frame with another identifier)
    not_data,      ///< extended, remote or error frame
    bad_length,    ///< length differs from the DBC's
    out_of_range,  ///< a value beyond what the receiver can represent or an undefined enum value
};

[[nodiscard]] hal::CanFrame encode(const HandleForceTorque& message);
[[nodiscard]] hal::CanFrame encode(const InsertionRoll& message);
[[nodiscard]] hal::CanFrame encode(const BoxStatus& message);
[[nodiscard]] hal::CanFrame encode(const KineticEstimate& message);
[[nodiscard]] hal::CanFrame encode(const ContactSummary& message);
[[nodiscard]] hal::CanFrame encode(const Alarms& message);
[[nodiscard]] hal::CanFrame encode(const BoxCounter& message);
[[nodiscard]] hal::CanFrame encode(const EstimateEvidence& message);
[[nodiscard]] hal::CanFrame encode(const StationForces& message);

[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, HandleForceTorque& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, InsertionRoll& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, BoxStatus& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, KineticEstimate& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, ContactSummary& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, Alarms& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, BoxCounter& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, EstimateEvidence& message);
[[nodiscard]] DecodeResult decode(const hal::CanFrame& frame, StationForces& message);

}  // namespace scopekin::protocol
