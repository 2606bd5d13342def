// The scorecard's combination of case scores (host_sim/evaluate/scorecard.hpp): pooled counts and
// order statistics over cases whose scores are written here by hand, the CSV's shape for scored
// and unscored cases, and the procedures' outcome (cecal intubation per style, insertion at the
// cecum) only where physician runs report it.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "host_sim/evaluate/scorecard.hpp"

namespace scopekin::evaluate {
namespace {

/// A complete case whose estimators all score: tip RMS `tip`, one loop episode (detected or
/// not), `false_alarms` false alarms in 60 s.
Json scored(const std::string& name, double tip, bool detected, int false_alarms,
            const Json& procedure = nullptr) {
    Json alarm = {{"episodes", 1},
                  {"detected", detected ? 1 : 0},
                  {"late", 0},
                  {"missed", detected ? 0 : 1},
                  {"false_alarms", false_alarms},
                  {"scored_s", 60.0},
                  {"detected_share", detected ? 1.0 : 0.0},
                  {"false_alarms_per_10min", false_alarms * 10.0},
                  {"latency_s", Json::array({detected ? Json(0.2) : Json()})},
                  {"linger_s", Json::array()}};
    Json none = alarm;
    none["episodes"] = 0;
    none["detected"] = 0;
    none["missed"] = 0;
    none["false_alarms"] = 0;
    none["latency_s"] = Json::array();
    Json estimators = Json::object();
    for (const Estimator& e : estimator_registry())
        estimators[e.name] = {{"label", e.label},
                              {"tip_error_mm", {{"rms", tip}, {"max", 2 * tip}}},
                              {"force_error_N", nullptr},
                              {"loop_alarm", alarm},
                              {"warning_alarm", none},
                              {"critical_alarm", none},
                              {"fault_share", {{"depth_outside_model", 0.5}}}};
    return {{"case", name},         {"style", "careful_expert"}, {"folder", "cases/" + name},
            {"status", "complete"}, {"duration_s", 60.0},        {"wall_time_s", 6.0},
            {"periods", 12000},     {"procedure", procedure},    {"estimators", estimators}};
}

TEST(Scorecard, PoolsCountsAndTakesOrderStatisticsOverTheCases) {
    const std::vector<Json> cases{scored("a", 10, true, 0), scored("b", 20, false, 1),
                                  scored("c", 30, true, 2), scored("d", 40, true, 0),
                                  unscored_case("e", "careful_expert", "cases/e", "failed", "x")};
    const Json o = aggregate(cases);
    EXPECT_EQ(o["cases"], 5);
    EXPECT_EQ(o["scored"], 4);
    ASSERT_EQ(o["not_scored"].size(), 1U);
    const Json& e = o["estimators"][0];
    EXPECT_EQ(e["tip_error_rms_mm"]["cases"], 4);
    EXPECT_DOUBLE_EQ(e["tip_error_rms_mm"]["median"].get<double>(), 25.0);
    EXPECT_DOUBLE_EQ(e["tip_error_rms_mm"]["p90"].get<double>(), 37.0);  // 30 + 0.7 x 10
    EXPECT_DOUBLE_EQ(e["tip_error_rms_mm"]["worst"].get<double>(), 40.0);
    EXPECT_TRUE(e["force_error_rms_N"]["median"].is_null());
    EXPECT_EQ(e["loop_alarm"]["episodes"], 4);
    EXPECT_EQ(e["loop_alarm"]["detected"], 3);
    EXPECT_DOUBLE_EQ(e["loop_alarm"]["detected_share"].get<double>(), 0.75);
    // 3 false alarms in 240 s: 7.5 per 10 minutes.
    EXPECT_DOUBLE_EQ(e["loop_alarm"]["false_alarms_per_10min"].get<double>(), 7.5);
    EXPECT_DOUBLE_EQ(e["fault_share"]["depth_outside_model"]["pooled"].get<double>(), 0.5);
    EXPECT_EQ(o["worst_cases"], Json::array({"d", "c", "b"}));
    EXPECT_TRUE(o["procedure"].is_null());  // no physician run: n/a
    const std::string md = scorecard_markdown(o, "set", "");
    EXPECT_NE(md.find("| 25 / 37 / 40 |"), std::string::npos) << md;
    EXPECT_NE(md.find("3 of 4 (75 %; 0 late, 1 missed)"), std::string::npos) << md;
    EXPECT_NE(md.find("n/a (no case of this set reports"), std::string::npos) << md;
}

TEST(Scorecard, ProceduresOutcomeFromPhysicianRuns) {
    auto physician = [](bool reached, double insertion) {
        return Json{{"kind", "physician"},
                    {"style", "careful_expert"},
                    {"cecum_reached", reached},
                    {"cecum_time_s", reached ? Json(300.0) : Json()},
                    {"insertion_at_cecum_mm", reached ? Json(insertion) : Json()}};
    };
    std::vector<Json> cases{scored("a", 1, true, 0, physician(true, 950)),
                            scored("b", 1, true, 0, physician(true, 1400)),
                            scored("c", 1, true, 0, physician(false, 0)),
                            scored("d", 1, true, 0, physician(true, 1100))};
    cases[3]["style"] = "hurried_trainee";
    const Json p = aggregate(cases)["procedure"];
    EXPECT_EQ(p["physician_cases"], 4);
    EXPECT_EQ(p["by_style"]["careful_expert"]["cases"], 3);
    EXPECT_EQ(p["by_style"]["careful_expert"]["cecum_reached"], 2);
    EXPECT_EQ(p["by_style"]["hurried_trainee"]["cecum_reached"], 1);
    EXPECT_EQ(p["under_1330_mm"]["cases"], 2);  // 950 and 1100 of 950, 1100, 1400
    EXPECT_EQ(p["under_1330_mm"]["of"], 3);
}

TEST(Scorecard, CsvRowsHaveTheHeadersCellsScoredOrNot) {
    const auto cells = [](const std::string& line) {
        return std::count(line.begin(), line.end(), ',') + 1;
    };
    const auto header = cells(scorecard_csv_header());
    for (const Json& c : {scored("a", 1, true, 0),
                          unscored_case("b", "x", "cases/b", "failed", "a, quoted \"message\"")}) {
        const auto rows = scorecard_csv_rows(c);
        EXPECT_EQ(rows.size(), estimator_registry().size());
        for (const std::string& row : rows)
            EXPECT_EQ(cells(row), header) << row;
    }
}

TEST(Scorecard, TheContactLevelIsScoredPeriodByPeriod) {
    // Ten periods of a true largest force and a level; >= 10 N in 5 periods (all with the level
    // up), under 9 N in 4 (up in 1); >= 14 N in 3 (critical in all 3), under 12.6 N in 6 (none).
    CaseRun run;
    run.status = "complete";
    for (int k = 1; k <= 10; ++k)
        run.time_s.push_back(0.005 * k);
    run.true_max_station_force_N = {5, 5, 9.5, 12, 14, 15, 15, 13, 8, 5};
    run.true_tip_path_mm.assign(10, 0.0);
    EstimatorOutput o;
    o.loop_alarm.assign(10, 0);
    o.contact_level = {0, 0, 0, 1, 2, 2, 2, 2, 1, 0};
    const std::vector<EstimatorOutput> outputs(estimator_registry().size(), o);
    const Json c = score_case("a", "careful_expert", "cases/a", run, outputs);
    const Json& p = c["estimators"]["box"]["contact_level_periods"];
    EXPECT_EQ(p["warning_10N"],
              Json({{"periods_over", 5}, {"up_over", 5}, {"periods_below", 4}, {"up_below", 1}}));
    EXPECT_EQ(p["critical_14N"],
              Json({{"periods_over", 3}, {"up_over", 3}, {"periods_below", 6}, {"up_below", 0}}));
    const Json o2 = aggregate({c, c});
    const Json& pooled = o2["estimators"][0]["contact_level_periods"]["warning_10N"];
    EXPECT_EQ(pooled["periods_over"], 10);
    EXPECT_DOUBLE_EQ(pooled["up_over_share"].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(pooled["up_below_share"].get<double>(), 0.25);
    const std::string md = scorecard_markdown(o2, "set", "");
    EXPECT_NE(
        md.find(
            "up in the periods the truth is over it / under 90 % of it (pooled) | 100 / 25 % |"),
        std::string::npos)
        << md;
}

}  // namespace
}  // namespace scopekin::evaluate
