#include "simulate/simulate_imperfection_options.h"

#include <cmath>
#include <cstdlib>

namespace gmm_localization {
namespace tools {
Result<double> parseOptionNumber(const std::string& opt, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(d))
    return Result<double>::failure("option " + opt + ": '" + v + "' is not a number");
  return d;
}

namespace {

/// "MIN,MAX" with MIN <= MAX.
Status range(const std::string& opt, const std::string& v, double* lo, double* hi) {
  const size_t comma = v.find(',');
  auto a = parseOptionNumber(opt, v.substr(0, comma));
  auto b = parseOptionNumber(opt, comma == std::string::npos ? "" : v.substr(comma + 1));
  if (!a || !b || *a > *b)
    return Status::failure("option " + opt + ": expected MIN,MAX with MIN <= MAX, got '" + v + "'");
  *lo = *a;
  *hi = *b;
  return Status::success();
}

Result<uint64_t> seed(const std::string& opt, const std::string& v) {
  auto d = parseOptionNumber(opt, v);
  if (!d) return Result<uint64_t>::failure(d.error());
  if (*d < 0.0 || *d != std::floor(*d))
    return Result<uint64_t>::failure("option " + opt + ": '" + v + "' is not a seed (>= 0)");
  return static_cast<uint64_t>(*d);
}

}  // namespace

Result<bool> applyImperfectionOption(const std::string& name, const std::string& v,
                                     sim::SimulationConfig* c, ImperfectionFlags* flags) {
  using R = Result<bool>;
  sim::ExtrinsicErrorConfig& e = c->extrinsic_error;
  sim::MapAgingConfig& a = c->pass.aging;
  Status s = Status::success();
  if (name == "--extrinsic-error") {
    auto m = sim::parseExtrinsicErrorMode(v);
    if (!m) return R::failure("option --extrinsic-error: " + m.error());
    e.mode = *m;
    return true;
  }
  if (name == "--aging") {
    auto m = sim::parseMapAgingMode(v);
    if (!m) return R::failure("option --aging: " + m.error());
    a.mode = *m;
    return true;
  }
  if (name.rfind("--extrinsic-error-", 0) == 0) {
    flags->extrinsic_override = name;
    if (name == "--extrinsic-error-m") {
      s = range(name, v, &e.translation_min_m, &e.translation_max_m);
    } else if (name == "--extrinsic-error-deg") {
      s = range(name, v, &e.rotation_min_deg, &e.rotation_max_deg);
    } else if (name == "--extrinsic-error-seed") {
      auto n = seed(name, v);
      if (!n) return R::failure(n.error());
      e.seed = *n;
    } else {
      return false;
    }
    if (!s) return R::failure(s.error());
    return true;
  }
  if (name.rfind("--aging-", 0) == 0) {
    flags->aging_override = name;
    if (name == "--aging-tree-growth") {
      s = range(name, v, &a.tree_growth_min_m, &a.tree_growth_max_m);
    } else if (name == "--aging-seed") {
      auto n = seed(name, v);
      if (!n) return R::failure(n.error());
      a.seed = *n;
    } else {
      double* target = name == "--aging-sites-per-km"        ? &a.sites_per_km
                       : name == "--aging-containers-per-km" ? &a.containers_per_km
                       : name == "--aging-tree-share"        ? &a.tree_share
                       : name == "--aging-repaved-per-km"    ? &a.repaved_per_km
                                                             : nullptr;
      if (target == nullptr) return false;
      auto d = parseOptionNumber(name, v);
      if (!d) return R::failure(d.error());
      *target = *d;
    }
    if (!s) return R::failure(s.error());
    return true;
  }
  return false;
}

Status checkImperfectionOptions(const sim::SimulationConfig& c, const ImperfectionFlags& flags) {
  // An override without its mode would silently do nothing.
  if (!flags.extrinsic_override.empty() && c.extrinsic_error.mode == sim::ExtrinsicErrorMode::kNone)
    return Status::failure("option " + flags.extrinsic_override +
                           " needs --extrinsic-error realistic");
  if (!flags.aging_override.empty() && c.pass.aging.mode == sim::MapAgingMode::kNone)
    return Status::failure("option " + flags.aging_override + " needs --aging realistic");
  if (c.pass.aging.mode != sim::MapAgingMode::kNone && c.pass.type == sim::PassType::kMapping)
    return Status::failure(
        "option --aging: the mapping pass is the reference the town ages from; age a "
        "localization pass (--pass downtown or snowy)");
  const Status e = c.extrinsic_error.validate();
  if (!e) return e;
  return c.pass.aging.validate();
}

}  // namespace tools
}  // namespace gmm_localization
