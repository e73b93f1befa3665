// Unknown keys are named (ros/params.h): a ParamSource records the keys its loaders read, and the
// keys present that no loader read - typos that would silently take the default - come out as
// "unknown parameter <full name> (typo? it is ignored)". Tree-backed sources stand in for the
// parameter server (no master here); the shipped config/*.yaml files, with the keys the shipped
// launch files add, give no warning, through the nodelets' loaders and through `evaluate`.
#include "gmm_localization/ros/params.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "evaluate/evaluate_yaml.h"
#include "gmm_localization/ros/cloud_merger_options.h"
#include "gmm_localization/ros/ekf_node_options.h"
#include "gmm_localization/ros/global_start_options.h"
#include "gmm_localization/ros/gnss_initializer_options.h"
#include "gmm_localization/ros/ins_adapter_options.h"
#include "gmm_localization/ros/map_server_options.h"
#include "gmm_localization/ros/matcher_options.h"

namespace gmm_localization {
namespace node {
namespace {

using XmlRpc::XmlRpcValue;

const std::string kConfig = GMM_CONFIG_DIR;

/// The shipped file as the nodelet sees it: the YAML, then the <param> keys the shipped launch
/// files (launch/localization.launch, launch/map_server.launch) set beside it.
XmlRpcValue shipped(const std::string& file) {
  XmlRpcValue tree = eval::yamlFileToXmlRpc(kConfig + "/" + file);
  auto set = [&tree](const std::string& key, XmlRpcValue v) { eval::setTreeValue(tree, key, v); };
  if (file == "map_server.yaml") {
    set("map_directory", XmlRpcValue(std::string("/maps/town")));
    set("map_frame", XmlRpcValue(std::string("map")));
    set("base_frame", XmlRpcValue(std::string("base_link")));
    XmlRpcValue position;
    position.setSize(2);
    position[0] = 1.0;
    position[1] = 2.0;
    set("initial_position", position);
  } else if (file == "matcher.yaml") {
    set("map_frame", XmlRpcValue(std::string("map")));
    set("base_frame", XmlRpcValue(std::string("base_link")));
    set("initial_pose/enabled", XmlRpcValue(true));
    for (const char* k : {"x", "y", "z", "yaw"}) set(std::string("initial_pose/") + k, 1.0);
    set("initial_pose/z_known", XmlRpcValue(true));
  } else if (file == "ekf.yaml") {
    set("map_frame", XmlRpcValue(std::string("map")));
    set("odom_frame", XmlRpcValue(std::string("odom")));
    set("base_frame", XmlRpcValue(std::string("base_link")));
  } else if (file == "cloud_merger.yaml") {
    set("output_frame", XmlRpcValue(std::string("base_link")));
  } else if (file == "ins_adapter.yaml") {
    set("driver_preset", XmlRpcValue(std::string("clearpath_applanix_bridge")));
    set("odom_frame", XmlRpcValue(std::string("odom")));
    set("base_frame", XmlRpcValue(std::string("base_link")));
  } else if (file == "global_start.yaml") {
    set("map_frame", XmlRpcValue(std::string("map")));
  } else if (file == "gnss_initializer.yaml") {
    set("heading_topic", XmlRpcValue(std::string("/gnss/heading")));
    set("map_frame", XmlRpcValue(std::string("map")));
    set("base_frame", XmlRpcValue(std::string("base_link")));
  }
  return tree;
}

ParamSource source(const XmlRpcValue& tree) { return ParamSource::fromTree(tree, "test.yaml:"); }

template <typename Options>
std::vector<std::string> warningsOf(Options (*load)(const ParamSource&), const XmlRpcValue& tree) {
  const ParamSource src = source(tree);
  load(src);
  return unknownParamWarnings(src);
}

TEST(UnknownParams, ShippedConfigsAndLaunchKeysGiveNoWarning) {
  EXPECT_EQ(warningsOf(loadMatcherOptions, shipped("matcher.yaml")), std::vector<std::string>{});
  EXPECT_EQ(warningsOf(loadEkfNodeOptions, shipped("ekf.yaml")), std::vector<std::string>{});
  EXPECT_EQ(warningsOf(loadMapServerOptions, shipped("map_server.yaml")),
            std::vector<std::string>{});
  EXPECT_EQ(warningsOf(loadCloudMergerOptions, shipped("cloud_merger.yaml")),
            std::vector<std::string>{});
  EXPECT_EQ(warningsOf(loadInsAdapterOptions, shipped("ins_adapter.yaml")),
            std::vector<std::string>{});
  EXPECT_EQ(warningsOf(loadGnssInitializerOptions, shipped("gnss_initializer.yaml")),
            std::vector<std::string>{});
  EXPECT_EQ(warningsOf(loadGlobalStartOptions, shipped("global_start.yaml")),
            std::vector<std::string>{});
  // Every key of each file is one its loader read (not merely covered by a namespace).
  const ParamSource src = source(shipped("matcher.yaml"));
  loadMatcherOptions(src);
  for (const std::string& key : src.presentParams()) {
    const std::vector<std::string> read = src.readParams();
    EXPECT_TRUE(std::find(read.begin(), read.end(), key) != read.end()) << key;
  }
  EXPECT_GT(src.presentParams().size(), 60u);
}

TEST(UnknownParams, AMisspeltKeyIsNamedWithItsFullName) {
  XmlRpcValue matcher = shipped("matcher.yaml");
  eval::setTreeValue(matcher, "acceptence/min_map_coverage", 0.5);  // namespace misspelt
  eval::setTreeValue(matcher, "registration/filter/voxel", 0.3);    // under a child source
  eval::setTreeValue(matcher, "window/sigma_multipler", 2.0);       // leaf misspelt
  EXPECT_EQ(warningsOf(loadMatcherOptions, matcher),
            (std::vector<std::string>{
                "unknown parameter test.yaml:acceptence/min_map_coverage (typo? it is ignored)",
                "unknown parameter test.yaml:registration/filter/voxel (typo? it is ignored)",
                "unknown parameter test.yaml:window/sigma_multipler (typo? it is ignored)"}));

  XmlRpcValue ekf = shipped("ekf.yaml");
  eval::setTreeValue(ekf, "policy/acceptence/min_coverage", 0.5);
  EXPECT_EQ(
      warningsOf(loadEkfNodeOptions, ekf),
      std::vector<std::string>{
          "unknown parameter test.yaml:policy/acceptence/min_coverage (typo? it is ignored)"});

  XmlRpcValue map_server = shipped("map_server.yaml");
  eval::setTreeValue(map_server, "raster_radius", 100.0);
  EXPECT_EQ(
      warningsOf(loadMapServerOptions, map_server),
      std::vector<std::string>{"unknown parameter test.yaml:raster_radius (typo? it is ignored)"});

  XmlRpcValue merger = shipped("cloud_merger.yaml");
  eval::setTreeValue(merger, "max_wait", 0.1);
  EXPECT_EQ(warningsOf(loadCloudMergerOptions, merger),
            std::vector<std::string>{"unknown parameter test.yaml:max_wait (typo? it is ignored)"});
}

TEST(UnknownParams, ReadingAValueCoversEverythingBelowIt) {
  XmlRpcValue tree;
  eval::setTreeValue(tree, "table/a", 1);
  eval::setTreeValue(tree, "table/b/c", 2);
  eval::setTreeValue(tree, "tables/a", 3);  // shares a prefix, not the namespace
  eval::setTreeValue(tree, "other", 4);
  const ParamSource src = source(tree);
  EXPECT_EQ(src.presentParams(),
            (std::vector<std::string>{"other", "table/a", "table/b/c", "tables/a"}));
  EXPECT_TRUE(src.hasParam("table"));  // a dictionary read as one value
  int v = 0;
  EXPECT_FALSE(src.child("x").getParam("missing", v));  // absent keys are recorded too
  EXPECT_EQ(src.readParams(), (std::vector<std::string>{"table", "x/missing"}));
  EXPECT_EQ(src.unreadParams(), (std::vector<std::string>{"other", "tables/a"}));
  EXPECT_EQ(src.rootName("tables/a"), "test.yaml:tables/a");
  // A copy shares the record.
  const ParamSource copy = src;
  EXPECT_TRUE(copy.getParam("other", v));
  EXPECT_EQ(src.unreadParams(), std::vector<std::string>{"tables/a"});
}

TEST(UnknownParams, EvaluateNamesUnknownKeysOfTheFilesAndOverrides) {
  using eval::loadMapServerYamlRaster;
  using eval::loadYamlOptions;
  std::ostringstream warn;
  loadYamlOptions(loadMatcherOptions, kConfig + "/matcher.yaml", {}, warn);
  loadYamlOptions(loadEkfNodeOptions, kConfig + "/ekf.yaml", {}, warn);
  loadMapServerYamlRaster(kConfig + "/map_server.yaml", warn);
  EXPECT_EQ(warn.str(), "");  // the shipped files: evaluate reads (or checks) every key

  loadYamlOptions(loadMatcherOptions, kConfig + "/matcher.yaml",
                  {"window/sigma_multipler=2.0", "window/sigma_multiplier=2.5"}, warn);
  EXPECT_EQ(warn.str(), "evaluate: unknown parameter " + kConfig +
                            "/matcher.yaml:window/sigma_multipler (typo? it is ignored)\n");

  // The map server's file: keys of the map server (not of the raster) do not warn; typos do.
  const std::string path = ::testing::TempDir() + "gmm_unknown_map_server.yaml";
  std::ofstream(path) << "z_step_m: 0.1\nraster_radius_m: 100.0\nhysteresis: 5.0\n";
  warn.str("");
  const RasterOptions r = loadMapServerYamlRaster(path, warn);
  EXPECT_DOUBLE_EQ(r.z_step_m, 0.1);
  EXPECT_EQ(warn.str(),
            "evaluate: unknown parameter " + path + ":hysteresis (typo? it is ignored)\n");
  // A file the map server would refuse (its own keys out of range): evaluate reads the raster
  // keys as before and reports nothing about the rest.
  std::ofstream(path) << "z_step_m: 0.1\nraster_radius_m: -1.0\nhysteresis: 5.0\n";
  warn.str("");
  EXPECT_DOUBLE_EQ(loadMapServerYamlRaster(path, warn).z_step_m, 0.1);
  EXPECT_EQ(warn.str(), "");
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
