// The default instantiation of the header-only AdvanceEfficiency template, compiled here with the
// firmware flags (no exceptions, no RTTI, strict warnings) on every preset.
#include "monitors/advance_efficiency.hpp"

namespace scopekin::monitors {

template class AdvanceEfficiency<kAdvanceWindowCapacity>;

}  // namespace scopekin::monitors
