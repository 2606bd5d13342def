// The estimators of the scorecard (host_sim/evaluate/estimators.hpp) on hand-made cases: the
// reference column of the definitions' own confirmation raises each alarm where the truth
// confirms the episode, so a loop confirmed 0.8 s after its dated onset scores late, not
// detected, under the 0.5 s rule, and a contact level (confirmed at its onset) scores detected.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "host_sim/evaluate/estimators.hpp"
#include "host_sim/evaluate/scoring.hpp"

namespace scopekin::evaluate {
namespace {

const Estimator& named(const std::string& name) {
    const std::vector<Estimator>& all = estimator_registry();
    const auto it =
        std::find_if(all.begin(), all.end(), [&](const Estimator& e) { return e.name == name; });
    if (it == all.end()) throw std::invalid_argument("no estimator " + name);
    return *it;
}

CaseRun ten_seconds() {
    CaseRun run;
    for (int k = 0; k < 2000; ++k)
        run.time_s.push_back(kPeriod_s * k);
    return run;
}

TEST(Estimators, TheDefinitionsConfirmationRaisesTheLoopAlarmAtTheConfirmationNotTheOnset) {
    CaseRun run = ten_seconds();
    // Onset dated to 2.0 s, confirmed (20 mm of excess) at 2.8 s, ended at 4.0 s; a second
    // episode confirmed 0.3 s after its onset.
    run.loop_episodes = {{2.0, 4.0, "N sigmoid", 2.8}, {6.0, 7.0, "N sigmoid", 6.3}};
    const EstimatorOutput o = named("definitions_confirmation").outputs(run, {});
    ASSERT_EQ(o.loop_alarm.size(), run.time_s.size());
    EXPECT_EQ(o.loop_alarm[559], 0);  // 2.795 s
    EXPECT_EQ(o.loop_alarm[560], 1);  // 2.800 s
    EXPECT_EQ(o.loop_alarm[799], 1);  // 3.995 s
    EXPECT_EQ(o.loop_alarm[800], 0);  // the end
    const AlarmScore s = score_alarm(run.time_s, o.loop_alarm, run.loop_episodes, kPeriod_s);
    EXPECT_EQ(s.detected, 1U);  // the second, 0.3 s after its onset
    EXPECT_EQ(s.late, 1U);      // the first, 0.8 s after
    EXPECT_EQ(s.false_alarms, 0U);
    EXPECT_TRUE(o.tip_path_mm.empty());  // a reference for the alarms only
    EXPECT_TRUE(o.max_force_N.empty());
}

TEST(Estimators, TheDefinitionsConfirmationFlagsAContactLevelAtItsOnset) {
    CaseRun run = ten_seconds();
    run.warning_episodes = {{1.0, 5.0, "", std::nullopt}};
    run.critical_episodes = {{2.0, 3.0, "", std::nullopt}};
    const EstimatorOutput o = named("definitions_confirmation").outputs(run, {});
    ASSERT_EQ(o.contact_level.size(), run.time_s.size());
    EXPECT_EQ(o.contact_level[199], 0);  // 0.995 s
    EXPECT_EQ(o.contact_level[200], 1);
    EXPECT_EQ(o.contact_level[400], 2);  // 2.0 s
    EXPECT_EQ(o.contact_level[600], 1);  // 3.0 s: critical over, still >= 10 N
    EXPECT_EQ(o.contact_level[1000], 0);
}

}  // namespace
}  // namespace scopekin::evaluate
