#include "evaluate/evaluate_yaml.h"

#include <cmath>
#include <limits>
#include <regex>

#include <yaml-cpp/yaml.h>

#include "gmm_localization/ros/map_server_options.h"

namespace gmm_localization {
namespace eval {
namespace {

using node::ConfigError;
using XmlRpc::XmlRpcValue;

// PyYAML's YAML 1.1 implicit resolvers (yaml/resolver.py), without sexagesimal numbers.
const std::regex kBool(
    "yes|Yes|YES|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF");
const std::regex kNull("~|null|Null|NULL|");
const std::regex kInt("[-+]?(0b[0-1_]+|0[0-7_]+|0o[0-7_]+|0|[1-9][0-9_]*|0x[0-9a-fA-F_]+)");
const std::regex kFloat(
    "[-+]?([0-9][0-9_]*)\\.[0-9_]*([eE][-+][0-9]+)?|\\.[0-9_]+([eE][-+][0-9]+)?|"
    "[-+]?\\.(inf|Inf|INF)|\\.(nan|NaN|NAN)");

std::string withoutUnderscores(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c != '_') out.push_back(c);
  }
  return out;
}

XmlRpcValue toBool(const std::string& s) {
  const char c = s[0];
  return XmlRpcValue(c == 'y' || c == 'Y' || c == 't' || c == 'T' || s == "on" || s == "On" ||
                     s == "ON");
}

XmlRpcValue toInt(const std::string& text, const std::string& where) {
  std::string s = withoutUnderscores(text);
  int sign = 1;
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) {
    sign = s[0] == '-' ? -1 : 1;
    s = s.substr(1);
  }
  int base = 10;
  if (s.rfind("0b", 0) == 0) {
    base = 2;
    s = s.substr(2);
  } else if (s.rfind("0x", 0) == 0) {
    base = 16;
    s = s.substr(2);
  } else if (s.rfind("0o", 0) == 0) {
    base = 8;
    s = s.substr(2);
  } else if (s.size() > 1 && s[0] == '0') {
    base = 8;
  }
  const long long v = sign * std::stoll(s, nullptr, base);
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    throw ConfigError(where + ": integer " + text + " does not fit 32 bits (XmlRpc int)");
  }
  return XmlRpcValue(static_cast<int>(v));
}

XmlRpcValue toDouble(const std::string& text) {
  const std::string s = withoutUnderscores(text);
  if (s.find("inf") != std::string::npos || s.find("Inf") != std::string::npos ||
      s.find("INF") != std::string::npos) {
    return XmlRpcValue(s[0] == '-' ? -HUGE_VAL : HUGE_VAL);
  }
  if (s.find("nan") != std::string::npos || s.find("NaN") != std::string::npos ||
      s.find("NAN") != std::string::npos) {
    return XmlRpcValue(std::numeric_limits<double>::quiet_NaN());
  }
  return XmlRpcValue(std::stod(s));
}

XmlRpcValue scalar(const YAML::Node& n, const std::string& where) {
  const std::string& s = n.Scalar();
  const std::string& tag = n.Tag();
  if (tag == "!") return XmlRpcValue(s);  // quoted: always a string
  if (tag == "tag:yaml.org,2002:str") return XmlRpcValue(s);
  if (tag == "tag:yaml.org,2002:int") return toInt(s, where);
  if (tag == "tag:yaml.org,2002:float") return toDouble(s);
  if (tag == "tag:yaml.org,2002:bool") return toBool(s);
  if (tag == "!degrees" || tag == "!radians") {
    // rosparam's angle tags: a number (PyYAML would evaluate an expression; numbers only here).
    const double v = std::stod(s);
    return XmlRpcValue(tag == "!degrees" ? v * M_PI / 180.0 : v);
  }
  if (!tag.empty() && tag != "?") throw ConfigError(where + ": unsupported YAML tag " + tag);
  if (std::regex_match(s, kBool)) return toBool(s);
  if (std::regex_match(s, kNull)) return XmlRpcValue();
  if (std::regex_match(s, kInt)) return toInt(s, where);
  if (std::regex_match(s, kFloat)) return toDouble(s);
  return XmlRpcValue(s);
}

/// "line L, column C: " of a YAML mark (1-based), empty when the mark is unknown.
std::string markText(const YAML::Mark& mark) {
  if (mark.is_null()) return {};
  return "line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) +
         ": ";
}

XmlRpcValue convert(const YAML::Node& n, const std::string& where) {
  switch (n.Type()) {
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      return XmlRpcValue();
    case YAML::NodeType::Scalar:
      return scalar(n, where);
    case YAML::NodeType::Sequence: {
      XmlRpcValue a;
      a.setSize(static_cast<int>(n.size()));
      int i = 0;
      for (const YAML::Node& e : n) {
        a[i] = convert(e, where + "[" + std::to_string(i) + "]");
        ++i;
      }
      return a;
    }
    case YAML::NodeType::Map: {
      XmlRpcValue s;
      s.begin();  // makes an empty struct
      for (const auto& kv : n) {
        // A parameter name is a scalar; a sequence or map key ("[a]: 1", "{a: 1}: 2") has no
        // name (rosparam refuses it too) and must not reach as<std::string>(), which throws
        // YAML::TypedBadConversion. A null key ("~: 1") reads as "null", as before.
        if (!kv.first.IsScalar() && !kv.first.IsNull()) {
          throw ConfigError(where + ": " + markText(kv.first.Mark()) + "a mapping key is a " +
                            (kv.first.IsSequence() ? "sequence" : "map") +
                            ", not a parameter name");
        }
        const std::string key = kv.first.as<std::string>();
        const XmlRpcValue v = convert(kv.second, where + "/" + key);
        if (v.valid()) s[key] = v;
      }
      return s;
    }
  }
  return XmlRpcValue();
}

}  // namespace

XmlRpc::XmlRpcValue yamlTextToXmlRpc(const std::string& text, const std::string& origin) {
  try {
    return convert(YAML::Load(text), origin);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ": YAML error: " + e.what());
  } catch (const std::logic_error& e) {  // stoll / stod out of range
    throw ConfigError(origin + ": bad number: " + e.what());
  }
}

XmlRpc::XmlRpcValue yamlFileToXmlRpc(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot read the file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": YAML error: " + e.what());
  }
  XmlRpcValue tree;
  try {
    tree = convert(root, path);
  } catch (const YAML::Exception& e) {
    // Any other yaml-cpp error while walking the tree (as in yamlTextToXmlRpc): a ConfigError
    // naming the file and, when yaml-cpp knows it, the line (e.msg is without yaml-cpp's own
    // "error at line" prefix).
    throw ConfigError(path + ": " + markText(e.mark) + "YAML error: " + e.msg);
  } catch (const std::logic_error& e) {
    if (dynamic_cast<const ConfigError*>(&e) == nullptr) {
      throw ConfigError(path + ": bad number: " + e.what());
    }
    throw;
  }
  if (tree.valid() && tree.getType() != XmlRpcValue::TypeStruct) {
    throw ConfigError(path + ": the document must be a map of parameters");
  }
  return tree;
}

void setTreeValue(XmlRpc::XmlRpcValue& tree, const std::string& key,
                  const XmlRpc::XmlRpcValue& value) {
  if (!tree.valid()) tree.begin();
  XmlRpcValue* node = &tree;
  size_t start = 0;
  while (true) {
    const size_t slash = key.find('/', start);
    const std::string part = key.substr(start, slash == std::string::npos ? slash : slash - start);
    if (slash == std::string::npos) {
      if (part.empty()) throw ConfigError("override key '" + key + "' ends with '/'");
      (*node)[part] = value;
      return;
    }
    if (!part.empty()) {
      XmlRpcValue& next = (*node)[part];
      if (next.getType() != XmlRpcValue::TypeStruct) {
        next = XmlRpcValue();
        next.begin();
      }
      node = &next;
    }
    start = slash + 1;
  }
}

node::ParamSource yamlParamSource(const std::string& path,
                                  const std::vector<std::string>& overrides) {
  XmlRpcValue tree = yamlFileToXmlRpc(path);
  for (const std::string& o : overrides) {
    const size_t eq = o.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw ConfigError("override '" + o + "' must read key=value");
    }
    const std::string key = o.substr(0, eq);
    const XmlRpcValue value = yamlTextToXmlRpc(o.substr(eq + 1), "override " + key);
    if (!value.valid()) throw ConfigError("override '" + o + "' has no value");
    setTreeValue(tree, key, value);
  }
  return node::ParamSource::fromTree(tree, path + ":");
}

void printUnknownParams(const node::ParamSource& source, std::ostream& warn) {
  for (const std::string& w : node::unknownParamWarnings(source)) {
    warn << "evaluate: " << w << std::endl;
  }
}

RasterOptions loadMapServerYamlRaster(const std::string& path, std::ostream& warn) {
  XmlRpcValue tree = yamlFileToXmlRpc(path);
  const RasterOptions raster =
      node::loadRasterOptions(node::ParamSource::fromTree(tree, path + ":"));
  if (!tree.valid() || !tree.hasMember("map_directory")) {
    setTreeValue(tree, "map_directory", XmlRpcValue(std::string("(map given to evaluate)")));
  }
  const node::ParamSource server = node::ParamSource::fromTree(tree, path + ":");
  try {
    node::loadMapServerOptions(server);  // reads every key of the map server (a superset)
  } catch (const ConfigError&) {
    return raster;  // the map server would refuse the file; evaluate does not use those keys
  }
  printUnknownParams(server, warn);
  return raster;
}

}  // namespace eval
}  // namespace gmm_localization
