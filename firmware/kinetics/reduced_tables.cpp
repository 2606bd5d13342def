#include "kinetics/reduced_tables.hpp"

namespace scopekin::kinetics {

namespace {

constexpr std::uint32_t kFnvOffset = 2166136261U;
constexpr std::uint32_t kFnvPrime = 16777619U;

std::uint32_t fnv_word(std::uint32_t hash, std::uint32_t word) noexcept {
    for (unsigned byte = 0; byte < 4U; ++byte) {  // bound: 4 bytes, little-endian order
        hash ^= (word >> (8U * byte)) & 0xFFU;
        hash *= kFnvPrime;
    }
    return hash;
}

std::uint32_t fnv_raw(std::uint32_t hash, Q16_16 value) noexcept {
    return fnv_word(hash, static_cast<std::uint32_t>(value.raw()));
}

}  // namespace

std::uint32_t reduced_tables_checksum(const ReducedTablesQ16& tables) noexcept {
    const ReducedModelHeader<Q16_16>& h = tables.head;
    std::uint32_t hash = kFnvOffset;
    hash = fnv_word(hash, static_cast<std::uint32_t>(h.stations));
    hash = fnv_word(hash, static_cast<std::uint32_t>(h.grid_points));
    hash = fnv_raw(hash, h.depth_start_mm);
    hash = fnv_raw(hash, h.depth_step_mm);
    hash = fnv_raw(hash, h.inverse_depth_step);
    hash = fnv_raw(hash, h.friction);
    hash = fnv_raw(hash, h.station_spacing_mm);
    for (std::size_t i = 0; i < tables.value_count; ++i) {  // bound: value_count (flash size)
        hash = fnv_word(hash, static_cast<std::uint32_t>(tables.values[i]));
    }
    return hash;
}

ReducedTablesFault check_reduced_tables(const ReducedTablesQ16* tables, std::size_t station_capacity) noexcept {
    if (tables == nullptr || tables->values == nullptr || tables->value_count == 0U) return ReducedTablesFault::missing;
    const ReducedModelHeader<Q16_16>& h = tables->head;
    if (h.stations < 1U || h.stations > station_capacity || h.grid_points < 2U ||
        h.grid_points > tables->value_count ||
        tables->value_count != h.grid_points * reduced_record_size(h.stations)) {
        return ReducedTablesFault::bad_shape;
    }
    if (h.depth_step_mm <= Q16_16{} || h.station_spacing_mm <= Q16_16{} || h.inverse_depth_step <= Q16_16{} ||
        h.depth_start_mm < Q16_16{}) {
        return ReducedTablesFault::bad_grid;
    }
    // 1/step as stored must be the rounded reciprocal (within 2 LSB of step * (1/step) = 1).
    const Q16_16 product = h.depth_step_mm * h.inverse_depth_step;
    const std::int32_t off = product.raw() - Q16_16::one_raw;
    if (off > 2 * (h.depth_step_mm.raw() >> 16) + 2 || -off > 2 * (h.depth_step_mm.raw() >> 16) + 2) {
        return ReducedTablesFault::bad_grid;
    }
    if (reduced_tables_checksum(*tables) != tables->checksum) return ReducedTablesFault::checksum_mismatch;
    return ReducedTablesFault::none;
}

}  // namespace scopekin::kinetics
