#include "gmm_localization/ros/params.h"

#include <cmath>

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

ParamSource::ParamSource(const ros::NodeHandle& nh) : nh_(nh) {}

ParamSource ParamSource::fromTree(XmlRpc::XmlRpcValue root, const std::string& origin) {
  ParamSource s;
  s.tree_ = std::make_shared<const XmlRpcValue>(std::move(root));
  s.origin_ = origin;
  return s;
}

ParamSource ParamSource::child(const std::string& ns) const {
  if (nh_) return ParamSource(ros::NodeHandle(*nh_, ns));
  ParamSource s = *this;
  s.prefix_ = joinedPrefix(prefix_, ns);
  return s;
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
  if (nh_) return nh_->hasParam(key);
  const XmlRpcValue* v = find(key);
  return v != nullptr && v->valid();
}

template <typename T>
bool ParamSource::get(const std::string& key, T& out) const {
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

}  // namespace node
}  // namespace gmm_localization
