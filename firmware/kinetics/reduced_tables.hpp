// reduced_tables.hpp — the reduced model's data as the firmware holds it: Q16.16 raw values in
// flash, generated from the full-order model by model/reduction (see reduced_kinetics.hpp for the
// method and the record layout) and checked by a checksum at init.
//
// Format: `values` holds grid_points records of reduced_record_size(stations) int32 raw Q16.16
// numbers each (record g at values + g * record_size), in the units of reduced_kinetics.hpp
// (mm, N, mm/N, dimensionless friction).  Every value was rounded to nearest from double by the
// generator, which refuses values outside Q16.16 (|x| >= 32768) instead of saturating them.
// Checksum: FNV-1a (32 bit) over the header's raw fields and then every value, each int32 taken
// as its four little-endian bytes — the same on every target, so a table that was truncated,
// damaged in flash or paired with the wrong header is caught at init (kinetics::init).
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
};

/// Generated reduced-model tables (Tables interface of reduced_step).
struct ReducedTablesQ16 {
    ReducedModelHeader<Q16_16> head{};
    const std::int32_t* values{nullptr};  ///< grid_points * record_size raw Q16.16 values
    std::size_t value_count{0};           ///< = grid_points * record_size
    std::uint32_t checksum{0};            ///< reduced_tables_checksum(*this) when intact
    const char* source{""};               ///< training scenario and generator, for reports

    [[nodiscard]] const ReducedModelHeader<Q16_16>& header() const noexcept { return head; }
    [[nodiscard]] std::size_t record_size() const noexcept { return reduced_record_size(head.stations); }
    /// Unchecked: indices come from reduced_step, bounded by the header validated at init.
    [[nodiscard]] Q16_16 value(std::size_t grid_point, std::size_t index) const noexcept {
        return Q16_16::from_raw(values[grid_point * record_size() + index]);
    }
};

/// FNV-1a over the header fields (stations, grid_points, then the raw values of depth_start,
/// depth_step, inverse_depth_step, friction, station_spacing) and the values.
[[nodiscard]] std::uint32_t reduced_tables_checksum(const ReducedTablesQ16& tables) noexcept;

/// Why a table set cannot be used (none = it can).
enum class ReducedTablesFault : std::uint8_t {
    none,
    missing,            ///< null pointer or no values
    bad_shape,          ///< stations outside 1..Stations, fewer than 2 grid points, or the value
                        ///< count does not match grid_points * record_size
    bad_grid,           ///< depth step or station spacing not positive, or 1/step inconsistent
    checksum_mismatch,  ///< the data is not what the generator wrote
};

/// Checks shape, grid and checksum for a state with `station_capacity` stations.
[[nodiscard]] ReducedTablesFault check_reduced_tables(const ReducedTablesQ16* tables,
                                                      std::size_t station_capacity) noexcept;

}  // namespace scopekin::kinetics
