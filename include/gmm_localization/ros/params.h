#pragma once
// Typed parameter loading with validation, done once at start (DESIGN.md 3): a missing key
// takes the default; a present key of the wrong type or out of range throws ConfigError naming
// the key, the value and the allowed range. onInit() catches it, logs NODELET_FATAL, rethrows.
//
// The loaders read a ParamSource, backed either by the parameter server (a ros::NodeHandle's
// namespace; implicit conversion, so `param(pnh, ...)` keeps working) or by a tree of XmlRpc
// values held in memory (the offline `evaluate` tool parses the same YAML files into one), so
// the nodelets and the tools share literally the same loaders, keys and checks.
//
// Unknown keys: a ParamSource records every key read through it (hasParam or getParam, also
// through its copies and children), so that after loading, the keys present in its namespace
// that no loader read - a typo, or an option that no longer exists, which would otherwise
// silently take its default - can be named: unreadParams(), unknownParamWarnings(), and for
// the nodelets loadNodeletOptions(), which warns with ROS_WARN once per such key.

#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

namespace gmm_localization {
namespace node {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A namespace of parameters. Keys are relative ("a/b/c" descends into nested namespaces).
class ParamSource {
 public:
  /// The parameter server, in nh's namespace (the nodelets' private handle).
  ParamSource(const ros::NodeHandle& nh);  // NOLINT(runtime/explicit): implicit on purpose

  /// An in-memory tree: `root` must be a struct (a namespace) or invalid (empty: no keys).
  /// `origin` prefixes the names in error messages (e.g. "config/matcher.yaml:").
  static ParamSource fromTree(XmlRpc::XmlRpcValue root, const std::string& origin);

  /// The sub-namespace `ns` (relative).
  ParamSource child(const std::string& ns) const;

  bool hasParam(const std::string& key) const;
  /// Reads the value at key into `out`; false when absent or of another type (out unchanged).
  /// Server: ros::NodeHandle::getParam. Tree: the same conversions (an int is accepted as a
  /// double; a double with an integral value as an int; list elements alike).
  bool getParam(const std::string& key, bool& out) const;
  bool getParam(const std::string& key, int& out) const;
  bool getParam(const std::string& key, double& out) const;
  bool getParam(const std::string& key, std::string& out) const;
  bool getParam(const std::string& key, std::vector<bool>& out) const;
  bool getParam(const std::string& key, std::vector<int>& out) const;
  bool getParam(const std::string& key, std::vector<double>& out) const;
  bool getParam(const std::string& key, std::vector<std::string>& out) const;

  /// The key's full name, for messages (server: NodeHandle::resolveName).
  std::string resolveName(const std::string& key) const;

  /// The keys of parameters present in the root namespace (the one this source or the source it
  /// was derived from with child() was made for), relative to it ("a/b/c"), sorted. Server: the
  /// master's parameter names under the namespace (ros::NodeHandle::getParamNames; a list or a
  /// dictionary set as one value lists its leaves); tree: the leaves of the tree (a list is one
  /// leaf). Empty when the master cannot be reached.
  std::vector<std::string> presentParams() const;
  /// The keys read so far through this source, its copies and its children (hasParam and
  /// getParam, present or not), relative to the root namespace, sorted.
  std::vector<std::string> readParams() const;
  /// presentParams() that were not read: neither the key itself nor a namespace or value above
  /// it (reading "a" as one value covers "a/b"). On the server, keys that nodelet's own loader
  /// reads in a standalone nodelet's private namespace (num_worker_threads) are not listed.
  /// Not thread-safe with concurrent reads through the same source.
  std::vector<std::string> unreadParams() const;
  /// The full name of a key relative to the root namespace, for messages (server: the resolved
  /// name, e.g. /localization/matcher/window/min_half_xy_m; tree: origin + key).
  std::string rootName(const std::string& key) const;

 private:
  ParamSource() = default;
  void recordRead(const std::string& key) const;
  /// The tree node at key (tree backend), nullptr when absent.
  const XmlRpc::XmlRpcValue* find(const std::string& key) const;
  template <typename T>
  bool get(const std::string& key, T& out) const;

  std::optional<ros::NodeHandle> nh_;
  std::string root_namespace_;  ///< server: the root NodeHandle's namespace ("/a/b")
  std::shared_ptr<const XmlRpc::XmlRpcValue> tree_;
  std::string origin_;
  std::string prefix_;  ///< namespace below the root, "" or "a/b/"
  /// Keys read, relative to the root; shared by copies and children.
  std::shared_ptr<std::set<std::string>> reads_ = std::make_shared<std::set<std::string>>();
};

/// One message per unreadParams() key: "unknown parameter <full name> (typo? it is ignored)".
std::vector<std::string> unknownParamWarnings(const ParamSource& src);

/// ROS_WARN "<node_name>: <message>" for each unknownParamWarnings() message.
void warnUnknownParams(const ParamSource& src, const std::string& node_name);

/// A nodelet's option loading: `load` reads pnh's namespace through one ParamSource, then
/// warnUnknownParams() names every parameter present there that `load` did not read (once per
/// key: the loading happens once, at start-up). Throws what `load` throws (ConfigError).
template <typename Options>
Options loadNodeletOptions(const ros::NodeHandle& pnh, const std::string& node_name,
                           Options (*load)(const ParamSource&)) {
  const ParamSource src(pnh);
  Options options = load(src);
  warnUnknownParams(src, node_name);
  return options;
}

/// Conversions of one XmlRpc value (tree backend); false when the type does not fit.
bool fromXmlRpc(const XmlRpc::XmlRpcValue& v, bool& out);
bool fromXmlRpc(const XmlRpc::XmlRpcValue& v, int& out);
bool fromXmlRpc(const XmlRpc::XmlRpcValue& v, double& out);
bool fromXmlRpc(const XmlRpc::XmlRpcValue& v, std::string& out);

template <typename T>
T param(const ParamSource& src, const std::string& key, const T& default_value) {
  if (!src.hasParam(key)) return default_value;
  T value;
  if (!src.getParam(key, value)) {
    throw ConfigError("parameter " + src.resolveName(key) + " has the wrong type");
  }
  return value;
}

/// As param(), and requires lo <= value <= hi.
template <typename T>
T param(const ParamSource& src, const std::string& key, const T& default_value, const T& lo,
        const T& hi) {
  const T value = param<T>(src, key, default_value);
  if (!(value >= lo && value <= hi)) {
    std::ostringstream os;
    os << "parameter " << src.resolveName(key) << " = " << value << " is outside [" << lo << ", "
       << hi << "]";
    throw ConfigError(os.str());
  }
  return value;
}

/// Throws ConfigError with `what` when `problem` is non-empty (for options' validate()).
inline void requireValid(const std::string& what, const std::string& problem) {
  if (!problem.empty()) throw ConfigError(what + ": " + problem);
}

}  // namespace node
}  // namespace gmm_localization
