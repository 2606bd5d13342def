// The evaluator answers a repeated request with the run it made: the same prediction bit for
// bit as a fresh run, and not counted as a run (host_sim/discrepancy/evaluator.hpp).
#include <gtest/gtest.h>

#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/evaluator.hpp"
#include "host_sim/discrepancy/model_spec.hpp"

namespace scopekin::discrepancy {
namespace {

/// A 1 s recording: the hand advances 20 -> 40 mm at 20 mm/s (1 kHz encoder), the handle force
/// measured every 10 ms (its values do not matter: nothing is compared here).
MeasuredRecording one_second_advance() {
    MeasuredRecording data;
    data.source = "test";
    for (int i = 0; i <= 1000; ++i)
        data.drive.push_back({i / 1000.0, 20.0 + 20.0 * i / 1000.0, 0.0});
    MeasuredSeries force;
    force.id = OutputId::handle_force;
    force.components = 1;
    for (int i = 0; i <= 100; ++i) {
        force.time_s.push_back(i / 100.0);
        force.value.emplace_back(0.0, 0.0, 0.0);
    }
    data.outputs.push_back(std::move(force));
    data.start_s = 0.0;
    data.end_s = 1.0;
    data.duration_s = 1.0;
    data.initial_insertion_mm = 20.0;
    return data;
}

bool same_bits(const ModelPrediction& a, const ModelPrediction& b) {
    if (a.ok != b.ok || a.steps != b.steps || a.outputs.size() != b.outputs.size()) return false;
    for (std::size_t o = 0; o < a.outputs.size(); ++o) {
        if (a.outputs[o].size() != b.outputs[o].size()) return false;
        for (std::size_t i = 0; i < a.outputs[o].size(); ++i)
            if (!(a.outputs[o][i].array() == b.outputs[o][i].array()).all()) return false;
    }
    return a.step_region == b.step_region;
}

TEST(DiscrepancyEvaluator, ARepeatedRequestIsTheRunMadeBeforeNotANewRun) {
    const ModelSpec model = read_model_spec(default_model(), "default");
    const MeasuredRecording data = one_second_advance();
    const nlohmann::json stiff = {{{"name", "ei_scale"}, {"factor", 1.3}}};
    const nlohmann::json soft = {{{"name", "ei_scale"}, {"factor", 0.7}}};

    Evaluator evaluator(model, data, 2);
    evaluator.run_baseline({});
    ASSERT_EQ(evaluator.runs(), 1U);
    // Asked twice in one batch: run once.
    const std::vector<ModelPrediction> batch =
        evaluator.run_all(std::vector<nlohmann::json>{stiff, soft, stiff});
    EXPECT_EQ(evaluator.runs(), 3U);
    EXPECT_EQ(evaluator.repeats(), 1U);
    ASSERT_TRUE(batch[0].ok && batch[1].ok);
    EXPECT_TRUE(same_bits(batch[0], batch[2]));
    EXPECT_FALSE(same_bits(batch[0], batch[1]));  // the two stiffnesses push differently
    // Asked again later: the stored run.
    const ModelPrediction again = evaluator.run(soft);
    EXPECT_EQ(evaluator.runs(), 3U);
    EXPECT_EQ(evaluator.repeats(), 2U);
    EXPECT_TRUE(same_bits(again, batch[1]));
    // ... which is what a fresh evaluator's run of it gives.
    Evaluator fresh(model, data, 1);
    fresh.run_baseline({});
    EXPECT_TRUE(same_bits(fresh.run(soft), again));
    // A value not asked before is a run.
    evaluator.run({{{"name", "ei_scale"}, {"factor", 1.0000001}}});
    EXPECT_EQ(evaluator.runs(), 4U);
}

}  // namespace
}  // namespace scopekin::discrepancy
