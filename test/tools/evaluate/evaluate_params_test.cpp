// The YAML parameter source of `evaluate` (src/tools/evaluate/evaluate_yaml.h) feeds the nodelets'
// own loaders (ros/params.h, matcher_options.h, ekf_node_options.h) without a master: the shipped
// config files load, typed as rosparam types them, overrides apply, and a bad value is reported
// with the file and key.
#include "evaluate/evaluate_yaml.h"

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "evaluate/evaluate_map.h"
#include "gmm_localization/ros/matcher_options.h"

namespace gmm_localization {
namespace eval {
namespace {

const std::string kConfig = GMM_CONFIG_DIR;

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(EvaluateParams, ShippedConfigFilesLoadThroughTheNodeletLoaders) {
  const node::MatcherOptions m =
      node::loadMatcherOptions(yamlParamSource(kConfig + "/matcher.yaml"));
  const node::EkfNodeOptions e = node::loadEkfNodeOptions(yamlParamSource(kConfig + "/ekf.yaml"));
  const RasterOptions r = loadRasterOptions(yamlParamSource(kConfig + "/map_server.yaml"));
  // Values written in the files (not the defaults in code).
  EXPECT_EQ(m.registration.filter.max_points, 4000u);
  EXPECT_DOUBLE_EQ(m.registration.filter.min_range_m, 3.0);
  EXPECT_DOUBLE_EQ(m.registration.heading_step_rad, 0.00873);
  EXPECT_EQ(m.base_frame, "base_link");
  EXPECT_FALSE(m.initial_pose_enabled);
  EXPECT_DOUBLE_EQ(e.ekf.min_measurement_variance, 1.0e-9);
  EXPECT_DOUBLE_EQ(e.ekf.process_noise_density[12], 1.0);
  EXPECT_DOUBLE_EQ(e.ekf.initial_variance[6], 400.0);
  EXPECT_FALSE(e.filter.match_mask[3]);
  EXPECT_TRUE(e.filter.match_mask[5]);
  EXPECT_EQ(r.num_layers, 6);
  EXPECT_DOUBLE_EQ(r.z_step_m, 0.1);
  // And into the pipeline, as evaluate does.
  EXPECT_EQ(node::pipelineOptions(m, e).validate(), "");
}

TEST(EvaluateParams, OverridesApplyOnTopOfTheFile) {
  const node::MatcherOptions m = node::loadMatcherOptions(
      yamlParamSource(kConfig + "/matcher.yaml",
                      {"initial_pose/enabled=true", "initial_pose/x=12",
                       "registration/filter/max_points=3000", "window/max_half_xy_m=7.5"}));
  EXPECT_TRUE(m.initial_pose_enabled);
  EXPECT_DOUBLE_EQ(m.initial_pose.x, 12.0);  // an int is accepted as a double
  EXPECT_EQ(m.registration.filter.max_points, 3000u);
  EXPECT_DOUBLE_EQ(m.policy.window.max_half_xy_m, 7.5);
}

TEST(EvaluateParams, ScalarsAreTypedAsRosparamTypesThem) {
  const std::string path = writeTemp("types.yaml",
                                     "a: yes\nb: 'true'\nc: 0x10\nd: 1.5e-3\ne: 1e-3\nf: 010\n"
                                     "g: [1, 2.5]\nh: ~\ni: -.inf\nns: {k: Off}\n");
  const node::ParamSource s = yamlParamSource(path);
  bool b = false;
  std::string str;
  int i = 0;
  double d = 0.0;
  EXPECT_TRUE(s.getParam("a", b) && b);
  EXPECT_TRUE(s.getParam("b", str) && str == "true");  // quoted: a string
  EXPECT_FALSE(s.getParam("b", b));
  EXPECT_TRUE(s.getParam("c", i) && i == 16);
  EXPECT_TRUE(s.getParam("d", d) && d == 1.5e-3);
  EXPECT_TRUE(s.getParam("e", str) && str == "1e-3");  // YAML 1.1: no dot, a string
  EXPECT_FALSE(s.getParam("e", d));
  EXPECT_TRUE(s.getParam("f", i) && i == 8);  // leading 0: octal
  std::vector<double> g;
  EXPECT_TRUE(s.getParam("g", g) && g.size() == 2 && g[1] == 2.5);
  std::vector<int> gi;
  EXPECT_FALSE(s.getParam("g", gi));  // 2.5 is not an int
  EXPECT_FALSE(s.hasParam("h"));      // null: no value
  EXPECT_TRUE(s.getParam("i", d) && std::isinf(d) && d < 0);
  EXPECT_TRUE(s.child("ns").getParam("k", b) && !b);
  EXPECT_TRUE(s.hasParam("ns/k"));
  EXPECT_FALSE(s.hasParam("ns/missing"));
  EXPECT_EQ(s.child("ns").resolveName("k"), path + ":ns/k");
}

TEST(EvaluateParams, BadValuesNameTheFileAndKey) {
  const std::string path =
      writeTemp("bad.yaml", "registration:\n  heading_step_rad: 0.5\n  exhaustive: 3\n");
  try {
    node::loadMatcherOptions(yamlParamSource(path));
    FAIL() << "expected a ConfigError";
  } catch (const node::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":registration/heading_step_rad"),
              std::string::npos)
        << e.what();
  }
  const std::string typed = writeTemp("typed.yaml", "deskew: 3\n");
  try {
    node::loadMatcherOptions(yamlParamSource(typed));
    FAIL() << "expected a ConfigError";
  } catch (const node::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("deskew has the wrong type"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(yamlParamSource(kConfig + "/no_such_file.yaml"), node::ConfigError);
  EXPECT_THROW(yamlParamSource(writeTemp("broken.yaml", "a: [1, 2\n")), node::ConfigError);
  EXPECT_THROW(yamlParamSource(kConfig + "/matcher.yaml", {"no_equals_sign"}), node::ConfigError);
}

// Fuzz reproducer test/fuzz/regressions/yaml_params/uncaught_bad_conversion_sequence_key.yaml
// ("[a]: 1"): a mapping key that is a sequence or a map threw YAML::TypedBadConversion out of
// yamlFileToXmlRpc instead of a ConfigError naming the file. Now a ConfigError with the file,
// the key's place in the tree and its line; the same through the overrides.
TEST(EvaluateParams, NonScalarMappingKeysAreConfigErrorsNamingTheFileAndLine) {
  struct Case {
    const char* text;
    const char* expected;  // after the path
  };
  for (const Case& c : {
           Case{"[a]: 1\n", ": line 1, column 1: a mapping key is a sequence"},
           Case{"{a: 1}: 2\n", ": line 1, column 1: a mapping key is a map"},
           Case{"ok: 1\nx: {[b]: 1}\n", "/x: line 2, column 5: a mapping key is a sequence"},
           Case{"ns:\n  inner:\n    ? [1, 2]\n    : 3\n",
                "/ns/inner: line 3, column 7: a mapping key is a sequence"},
       }) {
    const std::string path = writeTemp("key.yaml", c.text);
    try {
      yamlFileToXmlRpc(path);
      ADD_FAILURE() << "accepted " << c.text;
    } catch (const node::ConfigError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path + c.expected, 0), 0u) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a ConfigError: " << e.what();
    }
    EXPECT_THROW(yamlParamSource(path), node::ConfigError) << c.text;
  }
  try {
    yamlParamSource(kConfig + "/matcher.yaml", {"window={[a]: 1}"});
    ADD_FAILURE() << "accepted a sequence key in an override";
  } catch (const node::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("override window: line 1, column 2: a mapping key"),
              std::string::npos)
        << e.what();
  }
  // Scalar keys of every kind still load (a null key reads "null", as before).
  const node::ParamSource s = yamlParamSource(writeTemp("keys.yaml", "'q': 1\n7: 2\n~: 3\n"));
  int v = 0;
  EXPECT_TRUE(s.getParam("q", v) && v == 1);
  EXPECT_TRUE(s.getParam("7", v) && v == 2);
  EXPECT_TRUE(s.getParam("null", v) && v == 3);
}

}  // namespace
}  // namespace eval
}  // namespace gmm_localization
