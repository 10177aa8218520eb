// Gates (issue 72, docs/gates.md): the gate file and --require read into limits, and the limits
// evaluated on a report whose numbers are set here, so that each verdict is known in advance.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/report/gate.hpp"

namespace {

using namespace dyncal::host;

std::string gate_file(const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("dyncal_gate_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(path) << text;
  return path.string();
}

nlohmann::json fit_report() {
  return {{"joints",
           {{{"joint", 1}, {"r2_validation", 0.99}, {"rms_validation", 1.0}},
            {{"joint", 2}, {"r2_validation", 0.90}, {"rms_validation", 3.0}}}},
          {"condition_number", 800.0},
          {"params",
           {{{"name", "link1_ZZ_R"}, {"value", 1.0}, {"std", 0.1}, {"verdict", "determined"}},
            {{"name", "Fc1"}, {"value", -0.1}, {"std", 0.1}, {"verdict", "determined"}},        // 0 within 95 %
            {{"name", "Ia2"}, {"value", -0.5}, {"std", 0.1}, {"verdict", "not determined"}}}},  // contradicts
          {"links", {{{"link", 1}, {"mass", 4.0}, {"cad_mass", 2.0}, {"pseudo_inertia_min_eigenvalue", 1e-3}}}}};
}

TEST(Gates, FileAndRequireGiveTheLimits) {
  const std::string file = gate_file(
      "identify:\n  r2_validation_min: [0.95, 0.85]\n  rms_validation_max: 2.5\n  physics: true\n  "
      "condition_number_max: false\npayload:\n  payload_mass_min: 1\n");
  const Gate g = read_gate("identify", file, {"rms_validation_max=3.5", "link_mass_ratio_max=1.5"});
  ASSERT_EQ(g.limits.size(), 4u);  // condition_number_max: false is no limit; --require replaced rms
  const GateResult r = evaluate_gate(g, fit_report());
  // r2: joint 1 0.99 >= 0.95 passes, joint 2 0.90 >= 0.85 passes; rms <= 3.5 both pass; physics:
  // link 1 passes, Fc1 -0.1 + 1.96 * 0.1 >= 0 passes, Ia2 -0.5 + 0.196 < 0 fails; mass ratio 2 > 1.5 fails.
  int failed = 0;
  for (const GateItem& i : r.items) failed += i.passed ? 0 : 1;
  EXPECT_FALSE(r.passed);
  EXPECT_EQ(failed, 2);
  EXPECT_EQ(r.items.size(), 2u + 2u + 3u + 1u);
  const std::string text = gate_text(r);
  EXPECT_NE(text.find("failed: physics: Ia2's upper 95 % bound"), std::string::npos) << text;
  EXPECT_NE(text.find("failed: link_mass_ratio_max: link 1 mass"), std::string::npos) << text;
  EXPECT_EQ(gate_json(r)["passed"], false);
  std::filesystem::remove(file);
}

TEST(Gates, AQuantityTheReportLacksFails) {
  nlohmann::json report = fit_report();
  report.erase("links");  // a wls fit: no link masses
  const GateResult r = evaluate_gate(read_gate("identify", "", {"link_mass_ratio_max=3"}), report);
  ASSERT_EQ(r.items.size(), 1u);
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(std::isnan(r.items[0].value));
  EXPECT_TRUE(gate_json(r)["items"][0]["value"].is_null());
}

TEST(Gates, BadGatesAreOneLine) {
  auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([] { read_gate("identify", "", {"r2_min=0.9"}); }).find("its gates: r2_validation_min"),
            std::string::npos);
  EXPECT_NE(message([] { read_gate("identify", "", {"r2_validation_min=abc"}); }).find("not a finite number"),
            std::string::npos);
  EXPECT_NE(message([] { read_gate("identify", "", {"r2_validation_min"}); }).find("KEY=VALUE"), std::string::npos);
  const std::string no_section = gate_file("payload:\n  payload_mass_min: 1\n");
  EXPECT_NE(message([&] { read_gate("identify", no_section, {}); }).find("no 'identify' section"), std::string::npos);
  const std::string broken = gate_file("identify: [\n");
  EXPECT_NE(message([&] { read_gate("identify", broken, {}); }).find("not YAML or JSON"), std::string::npos);
  EXPECT_NE(message([] { read_gate("identify", "/nonexistent/gate.yaml", {}); }).find("cannot read"),
            std::string::npos);
  // A per-joint list of the wrong length.
  EXPECT_NE(message([] {
              evaluate_gate(read_gate("identify", "", {"r2_validation_min=0.9,0.9,0.9"}), fit_report());
            }).find("lists 3 values"),
            std::string::npos);
  std::filesystem::remove(no_section);
  std::filesystem::remove(broken);
}

}  // namespace
