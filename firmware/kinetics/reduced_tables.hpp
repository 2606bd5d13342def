// reduced_tables.hpp — the reduced model's data as the firmware holds it: Q16.16 raw values in
// flash, generated from the full-order model by model/reduction (see reduced_kinetics.hpp for the
// method and the record layout) and checked by a checksum at init.
//
// Format: `knot_values` holds the knot records of every segment, one after the other, without
// their slip signs (reduced_stored_knot_size(stations) int32 raw Q16.16 numbers each: per station
// p, g, f_n, f_t, f_s, then the kKnotValueCount knot values; segment i's knot k at record
// segments[i].first_knot + k); `slid_values` holds the slip signs (kStationSlid: -1, 0 or +1), one
// int8 per station per knot in the same order, so a sign costs 1 byte instead of a 4-byte Q16.16
// number (the tables lose 36 B per knot of 12 stations, 50 KB of the default's 1424 knots, and
// nothing else: the values read are the same bits); `compliance_values` holds the compliance
// records (reduced_compliance_size(stations) each, one every `compliance_every` knots of a
// segment, at segments[i].first_compliance + r).  Units as in reduced_kinetics.hpp (mm, N, mm/N).
// Every value was rounded to nearest from double by the generator, which refuses values outside
// Q16.16 (|x| >= 32768) instead of saturating them, and a slip sign that is not -1, 0 or +1.
// Checksum: FNV-1a (32 bit) over the header's fields (integers, and the raw Q16.16 numbers), then
// every knot value, every slip sign (as the int32 -1, 0 or 1) and every compliance value, each
// int32 taken as its four little-endian bytes — the same on every target, so a table that was
// truncated, damaged in flash or paired with the wrong header is caught at init (kinetics::init).
#pragma once

#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"
#include "kinetics/reduced_kinetics.hpp"

namespace scopekin::kinetics {

using fixed_point::Q16_16;

template <>
struct ReducedScalarTraits<Q16_16> {
    static Q16_16 from_int(int value) noexcept { return Q16_16::from_int(value); }
    /// floor(x): the integer part of the raw value (arithmetic shift).
    static int floor_int(Q16_16 x) noexcept {
        return static_cast<int>(x.raw() >> Q16_16::fraction_bits);
    }
};

/// Values stored per knot record: the station values but the slip sign, then the knot values.
constexpr std::size_t reduced_stored_knot_size(std::size_t stations) noexcept {
    return stations * kStationSlid + kKnotValueCount;
}
static_assert(kStationSlid + 1U == kStationValueCount, "the slip sign is a station's last value");

/// Generated reduced-model tables (Tables interface of reduced_step).
struct ReducedTablesQ16 {
    ReducedModelHeader<Q16_16> head{};
    const std::int32_t* knot_values{nullptr};  ///< knot records without slip signs, raw Q16.16
    std::size_t knot_value_count{0};
    const std::int8_t* slid_values{nullptr};  ///< slip signs, [knot][station]: -1, 0 or +1
    std::size_t slid_value_count{0};
    const std::int32_t* compliance_values{nullptr};  ///< compliance records, raw Q16.16
    std::size_t compliance_value_count{0};
    std::uint32_t checksum{0};  ///< reduced_tables_checksum(*this) when intact
    const char* source{""};     ///< training and generator, for reports

    [[nodiscard]] const ReducedModelHeader<Q16_16>& header() const noexcept { return head; }
    // Unchecked: indices come from reduced_step, bounded by the header validated at init.
    [[nodiscard]] Q16_16 station_value(std::size_t knot, std::size_t station,
                                       std::size_t value) const noexcept {
        return Q16_16::from_raw(knot_values[knot * reduced_stored_knot_size(head.stations) +
                                            station * kStationSlid + value]);
    }
    [[nodiscard]] Q16_16 slid(std::size_t knot, std::size_t station) const noexcept {
        return Q16_16::from_int(slid_values[knot * head.stations + station]);
    }
    [[nodiscard]] Q16_16 knot_value(std::size_t knot, std::size_t value) const noexcept {
        return Q16_16::from_raw(knot_values[knot * reduced_stored_knot_size(head.stations) +
                                            head.stations * kStationSlid + value]);
    }
    [[nodiscard]] Q16_16 compliance(std::size_t record, std::size_t index) const noexcept {
        return Q16_16::from_raw(
            compliance_values[record * reduced_compliance_size(head.stations) + index]);
    }
};

/// FNV-1a over the header (stations, compliance_every, raw friction and station spacing,
/// segment_count, then per segment kind, direction, raw key start, key step and hold depth,
/// knots, first_knot, first_compliance), the knot values, the slip signs and the compliance
/// values.
[[nodiscard]] std::uint32_t reduced_tables_checksum(const ReducedTablesQ16& tables) noexcept;

/// Why a table set cannot be used (none = it can).
enum class ReducedTablesFault : std::uint8_t {
    none,
    missing,            ///< null pointer or no values
    bad_shape,          ///< stations outside 1..Stations, no segment or too many, a segment with
                        ///< fewer than 2 knots or knots not a whole number of compliance
                        ///< intervals, records not laid out one segment after the other, value
                        ///< counts that do not match the records, or a slip sign other than
                        ///< -1, 0, +1
    bad_grid,           ///< a key step, the station spacing or mu not positive, a key start
                        ///< below 0, a segment that is neither a travel run (direction +-1)
                        ///< nor a hold run (from 0 s, at a depth >= 0), or segment 0 not a
                        ///< travel run trained advancing
    checksum_mismatch,  ///< the data is not what the generator wrote
};

/// Checks shape, grid and checksum for a state with `station_capacity` stations.
[[nodiscard]] ReducedTablesFault check_reduced_tables(const ReducedTablesQ16* tables,
                                                      std::size_t station_capacity) noexcept;

}  // namespace scopekin::kinetics
