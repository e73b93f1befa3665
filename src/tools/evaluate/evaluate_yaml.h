#pragma once
// YAML parameter files as a ParamSource (ros/params.h), so `evaluate` loads the nodelets'
// options offline, without a master, from the same config/*.yaml files and through the same
// loaders (node::loadMatcherOptions, node::loadEkfNodeOptions).
//
// Scalars are typed as `rosparam load` (PyYAML, YAML 1.1) types them before they reach the
// parameter server: quoted -> string; true/false/yes/no/on/off (any of the three casings) ->
// bool; decimal, 0x hex, 0o / leading-0 octal and 0b binary integers -> int; numbers with a dot
// (exponent with a sign, e.g. 1.0e-9), .inf, .nan -> double; ~ / null / empty -> no value;
// anything else -> string (so "1e-3" stays a string there and here, and a loader reading a
// double reports the wrong type in both). Standard tags !!str !!int !!float !!bool and
// rosparam's !degrees / !radians are honoured. Sexagesimal numbers (1:30) are not supported.

#include <iostream>
#include <string>
#include <vector>

#include <xmlrpcpp/XmlRpcValue.h>

#include "gmm_localization/core/raster/raster_options.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace eval {

/// Parses a YAML document into an XmlRpc tree (maps -> structs, sequences -> arrays).
/// Throws node::ConfigError naming the file and the problem (with the line where yaml-cpp knows
/// it), and nothing else: e.g. a mapping key that is a sequence or a map ("[a]: 1").
XmlRpc::XmlRpcValue yamlFileToXmlRpc(const std::string& path);
/// Parses YAML text (a whole document or one scalar, e.g. an override "0.25" or "[1, 2]").
XmlRpc::XmlRpcValue yamlTextToXmlRpc(const std::string& text, const std::string& origin);

/// Sets `value` at the slash-separated `key` of a struct tree, creating namespaces.
void setTreeValue(XmlRpc::XmlRpcValue& tree, const std::string& key,
                  const XmlRpc::XmlRpcValue& value);

/// The parameters of a YAML file, with "key=value" overrides (value in YAML syntax) applied
/// on top, as a ParamSource whose names read "<path>:<key>". Throws node::ConfigError.
node::ParamSource yamlParamSource(const std::string& path,
                                  const std::vector<std::string>& overrides = {});

/// Writes "evaluate: <message>" to `warn` for each node::unknownParamWarnings() message of
/// `source`: the keys of the file (and overrides) that no loader read through it.
void printUnknownParams(const node::ParamSource& source, std::ostream& warn);

/// Options from a YAML file (with overrides) through a nodelet's loader (e.g.
/// node::loadMatcherOptions), then printUnknownParams() on the file: a misspelt key warns by
/// name, as it does in the nodelet. Throws node::ConfigError.
template <typename Options>
Options loadYamlOptions(Options (*load)(const node::ParamSource&), const std::string& path,
                        const std::vector<std::string>& overrides = {},
                        std::ostream& warn = std::cerr) {
  const node::ParamSource source = yamlParamSource(path, overrides);
  Options options = load(source);
  printUnknownParams(source, warn);
  return options;
}

/// The raster keys of the map server's YAML file (node::loadRasterOptions; its errors throw
/// node::ConfigError as before). The file's other keys are the map server's, which `evaluate`
/// does not use: they are checked by running the map server's loader on the file (with a
/// placeholder map_directory when it has none), so that only keys neither loader reads warn. When
/// the map server's own checks fail on the file, no key is reported.
RasterOptions loadMapServerYamlRaster(const std::string& path, std::ostream& warn = std::cerr);

}  // namespace eval
}  // namespace gmm_localization
