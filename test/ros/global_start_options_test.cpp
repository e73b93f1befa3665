// The global start's options (config/global_start.yaml): defaults, a rough fix, and each bad
// combination refused with the parameter's name (tree-backed parameters, no master).
#include "gmm_localization/ros/global_start_options.h"

#include <string>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace node {
namespace {

using XmlRpc::XmlRpcValue;

XmlRpcValue pair(double a, double b) {
  XmlRpcValue v;
  v.setSize(2);
  v[0] = a;
  v[1] = b;
  return v;
}

GlobalStartOptions load(XmlRpcValue tree) {
  return loadGlobalStartOptions(ParamSource::fromTree(tree, "global_start.yaml:"));
}

std::string refusal(XmlRpcValue tree) {
  try {
    load(tree);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(GlobalStartOptions, DefaultsARoughFixAndRefusals) {
  XmlRpcValue empty;
  empty["wait_s"] = 5.0;
  const GlobalStartOptions d = load(empty);
  EXPECT_EQ(d.sweep.window_half_xy_m, 50.0);
  EXPECT_FALSE(d.sweep.hasRegion());

  XmlRpcValue fix;
  fix["region"]["centre"] = pair(120.0, -40.0);
  fix["region"]["radius_m"] = 150.0;
  const GlobalStartOptions f = load(fix);
  EXPECT_TRUE(f.sweep.hasRegion());
  EXPECT_EQ(f.sweep.region_x_m, 120.0);
  EXPECT_EQ(f.sweep.region_y_m, -40.0);

  XmlRpcValue no_radius;
  no_radius["region"]["centre"] = pair(1.0, 2.0);
  EXPECT_NE(refusal(no_radius).find("region/radius_m"), std::string::npos) << refusal(no_radius);
  XmlRpcValue no_centre;
  no_centre["region"]["radius_m"] = 100.0;
  EXPECT_NE(refusal(no_centre).find("needs region/centre"), std::string::npos)
      << refusal(no_centre);
  XmlRpcValue three;
  three["region"]["centre"].setSize(3);
  for (int i = 0; i < 3; ++i) three["region"]["centre"][i] = 1.0;
  EXPECT_NE(refusal(three).find("region/centre"), std::string::npos) << refusal(three);
  XmlRpcValue overlap;
  overlap["window_half_xy_m"] = 20.0;
  overlap["overlap_m"] = 30.0;
  EXPECT_NE(refusal(overlap).find("overlap_m"), std::string::npos) << refusal(overlap);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
