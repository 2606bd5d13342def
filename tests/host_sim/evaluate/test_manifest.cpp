// Evaluation manifests (host_sim/evaluate/manifest.hpp): the base scenario under each case, the
// keys a case may give, and the refusals, each naming the manifest, the case and the field.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "host_sim/evaluate/manifest.hpp"
#include "model/model_error.hpp"

namespace scopekin::evaluate {
namespace {

namespace fs = std::filesystem;

class Manifests : public ::testing::Test {
protected:
    // One folder per test process: CTest runs this fixture's tests side by side, and each
    // removes its folder at the end (a shared one was once removed under another's feet).
    fs::path dir = fs::temp_directory_path() /
                   ("scopekin_test_manifest_" + std::to_string(::getpid()) + "_" +
                    ::testing::UnitTest::GetInstance()->current_test_info()->name());
    void SetUp() override { fs::create_directories(dir); }
    void TearDown() override { fs::remove_all(dir); }
    fs::path write(const std::string& name, const std::string& text) {
        std::ofstream(dir / name) << text;
        return dir / name;
    }
    /// The message of the ModelError reading `text` throws ("" if none).
    std::string refusal(const std::string& text) {
        try {
            (void)read_manifest(write("m.json", text));
        } catch (const model::ModelError& e) {
            return e.what();
        }
        return "";
    }
};

const char* const kAdvance =
    R"("procedure": [{"action": "advance", "start_s": 0, "end_s": 2, "speed_mm_per_s": 20}])";

TEST_F(Manifests, CasesAreTheBaseWithTheManifestsAndTheirOwnKeysOver) {
    const fs::path m = write("m.json", std::string(R"({"name": "dev", "description": "d",
      "base": {"solver": {"time_step_s": 0.005}},
      "cases": [{"name": "a-1", "colon": {"bundled": "default"}, )") +
                                           kAdvance + R"(},
                {"name": "b_2", "patient": {"seed": 3}, "sensor_seed": 7, "initial_insertion_mm": 50, )" +
                                           kAdvance + "}]}");
    const Manifest manifest = read_manifest(m);
    EXPECT_EQ(manifest.name, "dev");
    ASSERT_EQ(manifest.cases.size(), 2U);
    const ManifestCase& a = manifest.cases[0];
    EXPECT_EQ(a.name, "a-1");
    EXPECT_EQ(a.sensor_seed, 1U);
    EXPECT_EQ(a.style, "scripted");
    EXPECT_EQ(a.scenario["scope"]["model"], "cf_q160l");  // the base
    EXPECT_EQ(a.scenario["initial_insertion_mm"], 20);
    EXPECT_EQ(a.scenario["solver"]["time_step_s"], 0.005);  // the manifest's base
    EXPECT_FALSE(a.scenario.contains("name"));
    const ManifestCase& b = manifest.cases[1];
    EXPECT_EQ(b.sensor_seed, 7U);
    EXPECT_EQ(b.scenario["initial_insertion_mm"], 50);  // the case's own
    EXPECT_EQ(b.scenario["patient"]["seed"], 3);
    EXPECT_FALSE(b.scenario.contains("sensor_seed"));
    EXPECT_EQ(base_scenario()["scope"]["length_mm"], 1700);
}

TEST_F(Manifests, APatientFileIsRelativeToTheManifestAndWrittenAbsolute) {
    fs::create_directories(dir / "patients");
    // A patient file as `scopekin patient` writes it is needed: refuse a missing one by path.
    const std::string message = refusal(std::string(R"({"name": "dev", "cases": [{"name": "a",
        "patient": {"file": "patients/missing.json"}, )") +
                                        kAdvance + "}]}");
    EXPECT_NE(message.find("cases[0] 'a'"), std::string::npos) << message;
    EXPECT_NE(message.find("missing.json"), std::string::npos) << message;
}

TEST_F(Manifests, RefusalsNameTheManifestTheCaseAndTheField) {
    const std::string ok_case = std::string(R"("colon": {"bundled": "default"}, )") + kAdvance;
    struct Bad {
        std::string text;
        std::string says;
    };
    const Bad bad[] = {
        {R"({"name": "dev", "cases": []})", "cases: lists no case"},
        {R"({"name": "dev", "cases": [], "extra": 1})", "extra: unknown key"},
        {R"({"name": "../dev", "cases": [{"name": "a"}]})", "not a file-safe name"},
        {R"({"name": "dev", "cases": [{"name": "a/b", )" + ok_case + "}]}",
         "cases[0].name: 'a/b' is not a file-safe name"},
        {R"({"name": "dev", "cases": [{)" + ok_case + "}]}", "cases[0]: has no 'name'"},
        {R"({"name": "dev", "cases": [{"name": "a", )" + ok_case + R"(}, {"name": "A", )" +
             ok_case + "}]}",
         "cases[1].name: 'A' is also the name of cases[0]"},
        {R"({"name": "dev", "cases": [{"name": "a", "procedur": [], )" + ok_case + "}]}",
         "cases[0] 'a': procedur: unknown key"},
        {R"({"name": "dev", "cases": [{"name": "a", "sensor_seed": -1, )" + ok_case + "}]}",
         "cases[0].sensor_seed: expected a whole number"},
        {R"({"name": "dev", "cases": [{"name": "a", "model": "m.json", )" + ok_case + "}]}",
         "cases[0].model: not taken in a manifest case"},
        {R"({"name": "dev", "cases": [{"name": "a", "procedure": []}]})",
         "cases[0] 'a': has neither 'colon' or 'patient'"},
        {R"({"name": "dev", "cases": [{"name": "a", )", "line 1"},  // a syntax error
    };
    for (const Bad& b : bad) {
        const std::string message = refusal(b.text);
        EXPECT_NE(message.find(b.says), std::string::npos)
            << "manifest " << b.text << "\n  refused with: '" << message << "'\n  expected: '"
            << b.says << "'";
        EXPECT_NE(message.find("m.json"), std::string::npos) << message;
    }
}

TEST(ManifestNames, FileSafeNames) {
    EXPECT_TRUE(is_file_safe("p0003-expert-s1"));
    EXPECT_TRUE(is_file_safe("a.b_c"));
    EXPECT_FALSE(is_file_safe(""));
    EXPECT_FALSE(is_file_safe(".hidden"));
    EXPECT_FALSE(is_file_safe("-x"));
    EXPECT_FALSE(is_file_safe("a b"));
    EXPECT_FALSE(is_file_safe(std::string(65, 'a')));
}

}  // namespace
}  // namespace scopekin::evaluate
