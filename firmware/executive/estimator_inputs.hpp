// estimator_inputs.hpp — the estimator's kinetics::Inputs, assembled once per period from the
// drivers' messages (messages/handle_samples.hpp, messages/em_tracker_samples.hpp).
//
// Copies only: no arithmetic on the samples, so the estimator sees exactly what the drivers
// published.  No heap, bounded loops (firmware rules).
#pragma once

#include "kinetics/kinetics_io.hpp"
#include "messages/em_tracker_samples.hpp"
#include "messages/handle_samples.hpp"

namespace scopekin::executive {

/// Keeps `sample` in `tracker` when it is valid: the latest valid sample of its source, marked
/// fresh and valid.  A flagged sample (fault_flags != 0) changes nothing.
void keep_tracker_sample(const messages::EmTrackerSample& sample, kinetics::TrackerInputs& tracker);

/// The period's Inputs: the handle samples (fresh bits per signal) and the tracker's latest.
[[nodiscard]] kinetics::Inputs assemble_inputs(const messages::HandleSamples& handle,
                                               const kinetics::TrackerInputs& tracker);

}  // namespace scopekin::executive
