#pragma once
// Typed parameter loading with validation, done once at start (DESIGN.md 3): a missing key
// takes the default; a present key of the wrong type or out of range throws ConfigError naming
// the key, the value and the allowed range. onInit() catches it, logs NODELET_FATAL, rethrows.
//
// The loaders read a ParamSource, backed either by the parameter server (a ros::NodeHandle's
// namespace; implicit conversion, so `param(pnh, ...)` keeps working) or by a tree of XmlRpc
// values held in memory (the offline `evaluate` tool parses the same YAML files into one), so
// the nodelets and the tools share literally the same loaders, keys and checks.

#include <memory>
#include <optional>
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

 private:
  ParamSource() = default;
  /// The tree node at key (tree backend), nullptr when absent.
  const XmlRpc::XmlRpcValue* find(const std::string& key) const;
  template <typename T>
  bool get(const std::string& key, T& out) const;

  std::optional<ros::NodeHandle> nh_;
  std::shared_ptr<const XmlRpc::XmlRpcValue> tree_;
  std::string origin_;
  std::string prefix_;  ///< namespace within the tree, "" or "a/b/"
};

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
