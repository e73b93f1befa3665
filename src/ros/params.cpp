#include "gmm_localization/ros/params.h"

#include <algorithm>
#include <cmath>

#include <ros/console.h>

namespace gmm_localization {
namespace node {
namespace {

using XmlRpc::XmlRpcValue;

/// "a//b/" -> {"a", "b"}.
std::vector<std::string> splitKey(const std::string& key) {
  std::vector<std::string> parts;
  std::string part;
  for (char c : key) {
    if (c == '/') {
      if (!part.empty()) parts.push_back(part);
      part.clear();
    } else {
      part.push_back(c);
    }
  }
  if (!part.empty()) parts.push_back(part);
  return parts;
}

std::string joinedPrefix(const std::string& prefix, const std::string& ns) {
  std::string out = prefix;
  for (const std::string& p : splitKey(ns)) out += p + "/";
  return out;
}

template <typename T>
bool listFromXmlRpc(const XmlRpcValue& v, std::vector<T>& out) {
  if (v.getType() != XmlRpcValue::TypeArray) return false;
  std::vector<T> values(static_cast<size_t>(v.size()));
  for (int i = 0; i < v.size(); ++i) {
    T element;
    if (!fromXmlRpc(v[i], element)) return false;
    values[static_cast<size_t>(i)] = element;
  }
  out = std::move(values);
  return true;
}

// std::vector<bool> elements are proxies: fill through a plain bool.
bool listFromXmlRpc(const XmlRpcValue& v, std::vector<bool>& out) {
  if (v.getType() != XmlRpcValue::TypeArray) return false;
  std::vector<bool> values(static_cast<size_t>(v.size()));
  for (int i = 0; i < v.size(); ++i) {
    bool element = false;
    if (!fromXmlRpc(v[i], element)) return false;
    values[static_cast<size_t>(i)] = element;
  }
  out = std::move(values);
  return true;
}

bool convert(const XmlRpcValue& v, bool& out) { return fromXmlRpc(v, out); }
bool convert(const XmlRpcValue& v, int& out) { return fromXmlRpc(v, out); }
bool convert(const XmlRpcValue& v, double& out) { return fromXmlRpc(v, out); }
bool convert(const XmlRpcValue& v, std::string& out) { return fromXmlRpc(v, out); }
template <typename T>
bool convert(const XmlRpcValue& v, std::vector<T>& out) {
  return listFromXmlRpc(v, out);
}

/// "a/b/" + "c//d" -> "a/b/c/d".
std::string joinedKey(const std::string& prefix, const std::string& key) {
  std::string out = joinedPrefix(prefix, key);
  if (!out.empty()) out.pop_back();
  return out;
}

/// The leaves of a tree (a struct descends, anything else is a leaf), as "a/b/c".
void collectLeaves(const XmlRpcValue& v, const std::string& key, std::vector<std::string>& out) {
  if (v.getType() != XmlRpcValue::TypeStruct) {
    if (!key.empty()) out.push_back(key);
    return;
  }
  XmlRpcValue& node = const_cast<XmlRpcValue&>(v);  // begin()/end() are non-const
  for (auto it = node.begin(); it != node.end(); ++it) {
    collectLeaves(it->second, key.empty() ? it->first : key + "/" + it->first, out);
  }
}

/// True when `key` or a namespace or value above it was read ("a/b/c", "a/b", "a"): reading
/// "a" as one value (a dictionary) covers "a/b".
bool coveredByRead(const std::set<std::string>& reads, std::string key) {
  while (true) {
    if (reads.count(key) > 0) return true;
    const size_t slash = key.rfind('/');
    if (slash == std::string::npos) return false;
    key.resize(slash);
  }
}

/// Keys that nodelet's own Loader reads in the private namespace of a standalone nodelet
/// (`nodelet standalone`: the node's and the nodelet's private namespaces coincide).
const char* const kNodeletInfrastructureKeys[] = {"num_worker_threads"};

}  // namespace

// XmlRpcValue's conversion operators are non-const; the values are only read here.
bool fromXmlRpc(const XmlRpcValue& v, bool& out) {
  if (v.getType() != XmlRpcValue::TypeBoolean) return false;
  out = static_cast<bool&>(const_cast<XmlRpcValue&>(v));
  return true;
}

bool fromXmlRpc(const XmlRpcValue& v, int& out) {
  if (v.getType() == XmlRpcValue::TypeInt) {
    out = static_cast<int&>(const_cast<XmlRpcValue&>(v));
    return true;
  }
  if (v.getType() == XmlRpcValue::TypeDouble) {
    const double d = static_cast<double&>(const_cast<XmlRpcValue&>(v));
    // roscpp rounds a double to the nearest int; only an integral value is taken here.
    if (!std::isfinite(d) || d != std::round(d) || std::abs(d) > 2147483647.0) return false;
    out = static_cast<int>(d);
    return true;
  }
  return false;
}

bool fromXmlRpc(const XmlRpcValue& v, double& out) {
  if (v.getType() == XmlRpcValue::TypeDouble) {
    out = static_cast<double&>(const_cast<XmlRpcValue&>(v));
    return true;
  }
  if (v.getType() == XmlRpcValue::TypeInt) {
    out = static_cast<int&>(const_cast<XmlRpcValue&>(v));
    return true;
  }
  return false;
}

bool fromXmlRpc(const XmlRpcValue& v, std::string& out) {
  if (v.getType() != XmlRpcValue::TypeString) return false;
  out = static_cast<std::string&>(const_cast<XmlRpcValue&>(v));
  return true;
}

ParamSource::ParamSource(const ros::NodeHandle& nh) : nh_(nh), root_namespace_(nh.getNamespace()) {}

ParamSource ParamSource::fromTree(XmlRpc::XmlRpcValue root, const std::string& origin) {
  ParamSource s;
  s.tree_ = std::make_shared<const XmlRpcValue>(std::move(root));
  s.origin_ = origin;
  return s;
}

ParamSource ParamSource::child(const std::string& ns) const {
  ParamSource s = *this;  // shares the record of reads
  if (nh_) s.nh_.emplace(*nh_, ns);
  s.prefix_ = joinedPrefix(prefix_, ns);
  return s;
}

void ParamSource::recordRead(const std::string& key) const {
  const std::string k = joinedKey(prefix_, key);
  if (!k.empty()) reads_->insert(k);
}

const XmlRpc::XmlRpcValue* ParamSource::find(const std::string& key) const {
  if (!tree_) return nullptr;
  const XmlRpcValue* node = tree_.get();
  for (const std::string& part : splitKey(prefix_ + key)) {
    if (node->getType() != XmlRpcValue::TypeStruct || !node->hasMember(part)) return nullptr;
    node = &const_cast<XmlRpcValue&>(*node)[part];
  }
  return node;
}

bool ParamSource::hasParam(const std::string& key) const {
  recordRead(key);
  if (nh_) return nh_->hasParam(key);
  const XmlRpcValue* v = find(key);
  return v != nullptr && v->valid();
}

template <typename T>
bool ParamSource::get(const std::string& key, T& out) const {
  recordRead(key);
  if (nh_) return nh_->getParam(key, out);
  const XmlRpcValue* v = find(key);
  return v != nullptr && convert(*v, out);
}

bool ParamSource::getParam(const std::string& key, bool& out) const { return get(key, out); }
bool ParamSource::getParam(const std::string& key, int& out) const { return get(key, out); }
bool ParamSource::getParam(const std::string& key, double& out) const { return get(key, out); }
bool ParamSource::getParam(const std::string& key, std::string& out) const { return get(key, out); }
bool ParamSource::getParam(const std::string& key, std::vector<bool>& out) const {
  return get(key, out);
}
bool ParamSource::getParam(const std::string& key, std::vector<int>& out) const {
  return get(key, out);
}
bool ParamSource::getParam(const std::string& key, std::vector<double>& out) const {
  return get(key, out);
}
bool ParamSource::getParam(const std::string& key, std::vector<std::string>& out) const {
  return get(key, out);
}

std::string ParamSource::resolveName(const std::string& key) const {
  if (nh_) return nh_->resolveName(key);
  std::string name = prefix_;
  for (const std::string& p : splitKey(key)) name += p + "/";
  if (!name.empty()) name.pop_back();
  return origin_ + name;
}

std::string ParamSource::rootName(const std::string& key) const {
  const std::string k = joinedKey("", key);
  if (nh_) return root_namespace_ == "/" ? "/" + k : root_namespace_ + "/" + k;
  return origin_ + k;
}

std::vector<std::string> ParamSource::presentParams() const {
  std::vector<std::string> keys;
  if (nh_) {
    std::vector<std::string> names;
    if (!nh_->getParamNames(names)) return keys;
    const std::string ns = root_namespace_ == "/" ? "/" : root_namespace_ + "/";
    for (const std::string& name : names) {
      if (name.size() > ns.size() && name.compare(0, ns.size(), ns) == 0) {
        keys.push_back(joinedKey("", name.substr(ns.size())));
      }
    }
  } else if (tree_) {
    collectLeaves(*tree_, "", keys);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

std::vector<std::string> ParamSource::readParams() const {
  return std::vector<std::string>(reads_->begin(), reads_->end());
}

std::vector<std::string> ParamSource::unreadParams() const {
  std::vector<std::string> unread;
  for (const std::string& key : presentParams()) {
    bool known = coveredByRead(*reads_, key);
    if (!known && nh_) {
      for (const char* infrastructure : kNodeletInfrastructureKeys) known |= key == infrastructure;
    }
    if (!known) unread.push_back(key);
  }
  return unread;
}

std::vector<std::string> unknownParamWarnings(const ParamSource& src) {
  std::vector<std::string> out;
  for (const std::string& key : src.unreadParams()) {
    out.push_back("unknown parameter " + src.rootName(key) + " (typo? it is ignored)");
  }
  return out;
}

void warnUnknownParams(const ParamSource& src, const std::string& node_name) {
  for (const std::string& w : unknownParamWarnings(src)) {
    ROS_WARN("%s: %s", node_name.c_str(), w.c_str());
  }
}

}  // namespace node
}  // namespace gmm_localization
