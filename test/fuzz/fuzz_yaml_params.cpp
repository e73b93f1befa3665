// Fuzz target: YAML parameters -> validated options. The nodelets read their options from the
// parameter server (rosparam load of config/*.yaml), `evaluate` from the same files parsed with
// yaml-cpp (src/tools/evaluate/evaluate_yaml.h); both go through the same loaders
// (node::loadMatcherOptions, loadEkfNodeOptions, loadMapServerOptions, loadCloudMergerOptions,
// loadRasterOptions over a node::ParamSource, ros/params.h). Fuzzing the parameter server
// would need a ROS master, so the tree backend is fuzzed: the YAML parser of evaluate, the
// key=value overrides, the ParamSource conversions and every loader's range checks and
// validate() calls - the loaders and checks the nodelets run on the server's values.
// Input: a YAML document, then optionally a NUL byte and override lines "key=value".
// Contract: every failure is a node::ConfigError (any other exception escaping is a crash).
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "evaluate/evaluate_yaml.h"
#include "fuzz_file.h"
#include "gmm_localization/ros/cloud_merger_options.h"
#include "gmm_localization/ros/ekf_node_options.h"
#include "gmm_localization/ros/map_server_options.h"
#include "gmm_localization/ros/matcher_options.h"

namespace {

using namespace gmm_localization;

template <typename Options>
void load(Options (*loader)(const node::ParamSource&), const node::ParamSource& source) {
  try {
    (void)loader(source);
  } catch (const node::ConfigError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static fuzz::MemFile file("fuzz.yaml");
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t nul = input.find('\0');
  const std::string document = input.substr(0, nul);
  std::vector<std::string> overrides;
  if (nul != std::string::npos) {
    std::istringstream lines(input.substr(nul + 1));
    for (std::string line; std::getline(lines, line) && overrides.size() < 8;) {
      overrides.push_back(line);
    }
  }
  const std::string& path =
      file.set(reinterpret_cast<const uint8_t*>(document.data()), document.size());
  try {
    const node::ParamSource source = eval::yamlParamSource(path, overrides);
    load(&node::loadMatcherOptions, source);
    load(&node::loadEkfNodeOptions, source);
    load(&node::loadMapServerOptions, source);
    load(&node::loadCloudMergerOptions, source);
    load(&node::loadRasterOptions, source);
    (void)node::unknownParamWarnings(source);
  } catch (const node::ConfigError&) {
  }
  try {
    std::ostringstream warnings;
    (void)eval::loadMapServerYamlRaster(path, warnings);
  } catch (const node::ConfigError&) {
  }
  return 0;
}
