#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {

Significance assess_significance(const DiscrepancyContext& context) {
    const MeasuredRecording& data = context.data;
    const std::vector<double>& sigma = context.sigma;
    const double threshold = context.options.significance;
    Significance s;
    double worst_ratio = -1.0;
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        const double rms = rms_error(data, context.baseline, o, SampleSet::held_out);
        if (!assessable(sigma, o)) {
            s.outputs[output_name(data.outputs[o].id)] = {
                {"noise_sd", nullptr},
                {"held_out_rms", rms},
                {"assessed", false},
                {"why",
                 "its noise cannot be estimated from the data (the sensor reads 0 nearly all the "
                 "time)"}};
            continue;
        }
        const double ratio = rms / sigma[o];
        if (ratio > worst_ratio) {
            worst_ratio = ratio;
            s.most_affected = o;
        }
        s.any = s.any || ratio > threshold;
        s.outputs[output_name(data.outputs[o].id)] = {{"noise_sd", sigma[o]},
                                                      {"held_out_rms", rms},
                                                      {"assessed", true},
                                                      {"rms_over_noise", ratio},
                                                      {"significant", ratio > threshold}};
    }
    return s;
}

}  // namespace scopekin::discrepancy
