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
    hash = fnv_word(hash, static_cast<std::uint32_t>(h.compliance_every));
    hash = fnv_raw(hash, h.friction);
    hash = fnv_raw(hash, h.station_spacing_mm);
    hash = fnv_word(hash, static_cast<std::uint32_t>(h.segment_count));
    for (const ReducedSegment<Q16_16>& s : h.segments) {  // bound: kMaxReducedSegments
        hash = fnv_word(hash, static_cast<std::uint32_t>(s.kind));
        hash = fnv_word(hash, static_cast<std::uint32_t>(s.direction));
        hash = fnv_raw(hash, s.key_start);
        hash = fnv_raw(hash, s.key_step);
        hash = fnv_raw(hash, s.hold_depth_mm);
        hash = fnv_word(hash, static_cast<std::uint32_t>(s.knots));
        hash = fnv_word(hash, static_cast<std::uint32_t>(s.first_knot));
        hash = fnv_word(hash, static_cast<std::uint32_t>(s.first_compliance));
    }
    for (std::size_t i = 0; i < tables.knot_value_count;
         ++i) {  // bound: knot_value_count (flash size)
        hash = fnv_word(hash, static_cast<std::uint32_t>(tables.knot_values[i]));
    }
    for (std::size_t i = 0; i < tables.slid_value_count; ++i) {  // bound: slid_value_count
        hash = fnv_word(hash, static_cast<std::uint32_t>(std::int32_t{tables.slid_values[i]}));
    }
    for (std::size_t i = 0; i < tables.compliance_value_count;
         ++i) {  // bound: compliance_value_count
        hash = fnv_word(hash, static_cast<std::uint32_t>(tables.compliance_values[i]));
    }
    return hash;
}

ReducedTablesFault check_reduced_tables(const ReducedTablesQ16* tables,
                                        std::size_t station_capacity) noexcept {
    if (tables == nullptr || tables->knot_values == nullptr || tables->knot_value_count == 0U ||
        tables->slid_values == nullptr || tables->slid_value_count == 0U ||
        tables->compliance_values == nullptr || tables->compliance_value_count == 0U) {
        return ReducedTablesFault::missing;
    }
    const ReducedModelHeader<Q16_16>& h = tables->head;
    if (h.stations < 1U || h.stations > station_capacity || h.segment_count < 1U ||
        h.segment_count > kMaxReducedSegments || h.compliance_every < 1U ||
        h.compliance_every > 1000U) {
        return ReducedTablesFault::bad_shape;
    }
    std::size_t knots = 0;
    std::size_t records = 0;
    for (std::size_t i = 0; i < h.segment_count; ++i) {  // bound: kMaxReducedSegments
        const ReducedSegment<Q16_16>& s = h.segments[i];
        if (s.knots < 2U || s.knots > 100000U || (s.knots - 1U) % h.compliance_every != 0U ||
            s.first_knot != knots || s.first_compliance != records) {
            return ReducedTablesFault::bad_shape;
        }
        knots += s.knots;
        records += (s.knots - 1U) / h.compliance_every + 1U;
    }
    if (tables->knot_value_count != knots * reduced_stored_knot_size(h.stations) ||
        tables->slid_value_count != knots * h.stations ||
        tables->compliance_value_count != records * reduced_compliance_size(h.stations)) {
        return ReducedTablesFault::bad_shape;
    }
    for (std::size_t i = 0; i < tables->slid_value_count; ++i) {  // bound: slid_value_count
        if (tables->slid_values[i] < -1 || tables->slid_values[i] > 1)
            return ReducedTablesFault::bad_shape;
    }
    if (h.station_spacing_mm <= Q16_16{} || h.friction <= Q16_16{} ||
        h.segments[0].direction != 1 || h.segments[0].kind != kSegmentTravel) {
        return ReducedTablesFault::bad_grid;
    }
    for (std::size_t i = 0; i < h.segment_count; ++i) {  // bound: kMaxReducedSegments
        const ReducedSegment<Q16_16>& s = h.segments[i];
        const bool travel = s.kind == kSegmentTravel && (s.direction == 1 || s.direction == -1) &&
                            s.hold_depth_mm == Q16_16{};
        const bool hold = s.kind == kSegmentHold && s.direction == 1 && s.key_start == Q16_16{} &&
                          s.hold_depth_mm >= Q16_16{};
        if ((!travel && !hold) || s.key_step <= Q16_16{} || s.key_start < Q16_16{}) {
            return ReducedTablesFault::bad_grid;
        }
        // The last knot's key must be representable (no saturation in reduced_step).
        const std::int64_t end_raw =
            std::int64_t{s.key_start.raw()} +
            std::int64_t{s.key_step.raw()} * static_cast<std::int64_t>(s.knots - 1U);
        if (end_raw > std::int64_t{Q16_16::max().raw()}) return ReducedTablesFault::bad_grid;
    }
    if (reduced_tables_checksum(*tables) != tables->checksum)
        return ReducedTablesFault::checksum_mismatch;
    return ReducedTablesFault::none;
}

}  // namespace scopekin::kinetics
