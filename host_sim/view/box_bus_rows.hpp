#pragma once
// `scopekin display`: the box's page from what the box sends on the CAN bus (and the handle
// sensors' frames the display hears on the same bus): each period's frames decoded into the
// page's row of the box (host_sim::box_view_row's fields), nothing the bus does not carry.
//
// The box sends, every period, KineticEstimate (0x181, first), ContactSummary, Alarms,
// EstimateEvidence, one StationForces (round robin over the active stations), one BoxCounters,
// and BoxStatus every 20 periods or when a fault bit changes (last): firmware/README.md, "CAN
// protocol". A period's row is complete when the next KineticEstimate (or the end) comes.
#include <array>
#include <cstdint>
#include <functional>

#include <nlohmann/json.hpp>

#include "hal/can_bus.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::view {

class BoxBusRows {
public:
    /// `on_row(time_s, row)`: one box period, time_s from the first frame heard.
    using RowSink = std::function<void(double time_s, const nlohmann::ordered_json& row)>;
    explicit BoxBusRows(RowSink on_row) : on_row_(std::move(on_row)) {}

    /// One frame off the bus, stamped in µs (any origin, not decreasing).
    void feed(std::uint64_t timestamp_us, const hal::CanFrame& frame);
    /// The last period's row, if one is open (at the end of a log).
    void flush();

    std::uint64_t periods() const { return periods_; }
    /// Frames of the protocol's identifiers that did not decode (bad length, out of range).
    std::uint64_t refused() const { return refused_; }
    /// Frames of no identifier the display reads (error frames, foreign ids).
    std::uint64_t ignored() const { return ignored_; }

private:
    nlohmann::ordered_json row() const;

    RowSink on_row_;
    bool first_seen_ = false;
    std::uint64_t first_us_ = 0;
    bool open_ = false;  ///< a KineticEstimate opened a period not yet sent
    double period_s_ = 0;
    protocol::HandleForceTorque handle_{};
    protocol::InsertionRoll insertion_{};
    protocol::KineticEstimate estimate_{};
    protocol::ContactSummary summary_{};
    protocol::Alarms alarms_{};
    std::uint16_t kinetic_faults_ = 0;  ///< BoxStatus: the kinetics' FaultFlag bits
    struct Station {
        bool heard = false;
        fixed_point::Q16_16 path_mm{};
        fixed_point::Q16_16 normal_N{};
    };
    std::array<Station, 16> stations_{};
    std::uint64_t periods_ = 0, refused_ = 0, ignored_ = 0;
};

}  // namespace scopekin::view
