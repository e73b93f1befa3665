#include "build_map/build_map_options.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <sstream>

#include "build_map/build_map_georeference.h"
#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace tools {
namespace {

std::string text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::string resolutionRange() {
  return "[" + text(kMinMapResolutionM) + ", " + text(kMaxMapResolutionM) + "] m";
}

Result<std::vector<double>> parseNumberList(const std::string& option, const std::string& text,
                                            size_t count) {
  std::vector<double> v;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x)) {
      return Result<std::vector<double>>::failure(option + ": '" + item + "' is not a number");
    }
    v.push_back(x);
  }
  if (v.size() != count) {
    return Result<std::vector<double>>::failure(option + " needs " + std::to_string(count) +
                                                " comma-separated numbers, got '" + text + "'");
  }
  return v;
}

Result<Eigen::Isometry3d> parseTransform(const std::string& option, const std::string& text) {
  const size_t n = std::count(text.begin(), text.end(), ',') + 1;
  auto v = parseNumberList(option, text, n == 7 ? 7 : 6);
  if (!v) return Result<Eigen::Isometry3d>::failure(v.error());
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d((*v)[0], (*v)[1], (*v)[2]);
  if (n == 7) {
    Eigen::Quaterniond q((*v)[6], (*v)[3], (*v)[4], (*v)[5]);
    if (q.norm() < 1e-6) return Result<Eigen::Isometry3d>::failure(option + ": zero quaternion");
    t.linear() = q.normalized().toRotationMatrix();
  } else {
    const double d = M_PI / 180.0;
    t.linear() = (Eigen::AngleAxisd((*v)[5] * d, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd((*v)[4] * d, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd((*v)[3] * d, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  }
  return t;
}

namespace {

Result<double> number(const std::string& opt, const std::string& v) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || std::isnan(x)) {
    return Result<double>::failure(opt + ": '" + v + "' is not a number");
  }
  return x;
}

Result<int> integer(const std::string& opt, const std::string& v) {
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || x < INT32_MIN || x > INT32_MAX) {
    return Result<int>::failure(opt + ": '" + v + "' is not an integer");
  }
  return static_cast<int>(x);
}

}  // namespace

Result<BuildMapConfig> parseBuildMapArgs(int argc, char** argv) {
  using R = Result<BuildMapConfig>;
  BuildMapConfig c;
  MapBuilderOptions& b = c.builder;
  std::string error;
  GeoreferenceArgs geo;
  bool pose_topic_given = false;
  auto setInput = [&](InputKind k, const std::string& opt) {
    const bool more_pcd = k == InputKind::kPcd && c.input == InputKind::kPcd;
    if (c.input != InputKind::kNone && !more_pcd) error = opt + ": give exactly one input";
    c.input = k;
  };
  // Options with a value: name -> handler(value).
  using Handler = std::function<void(const std::string&, const std::string&)>;
  auto num = [&](double& out) {
    return Handler([&out, &error](const std::string& o, const std::string& v) {
      auto x = number(o, v);
      if (x)
        out = *x;
      else
        error = x.error();
    });
  };
  auto intg = [&](int& out) {
    return Handler([&out, &error](const std::string& o, const std::string& v) {
      auto x = integer(o, v);
      if (x)
        out = *x;
      else
        error = x.error();
    });
  };
  auto str = [&](std::string& out) {
    return Handler([&out](const std::string&, const std::string& v) { out = v; });
  };
  int k_max = b.em.max_components, seed = 1, spill_mb = 256;
  double pcd_batch = 1e6;
  std::string pcd_only;           // the last PCD-only option given
  std::string reflectivity_only;  // the last option of the reflectivity layer given
  ReflectivityLayerOptions& refl = b.reflectivity;
  auto reflNum = [&](double& out) {
    return Handler([&out, &error, &reflectivity_only](const std::string& o, const std::string& v) {
      auto x = number(o, v);
      if (x)
        out = *x;
      else
        error = x.error();
      reflectivity_only = o;
    });
  };
  std::map<std::string, Handler> valued = {
      {"--output", str(b.output_directory)},
      {"--out", str(b.output_directory)},  // the other tools' name
      {"--pcd",
       [&](const std::string& o, const std::string& v) {
         setInput(InputKind::kPcd, o);
         c.pcd_paths.push_back(v);
       }},
      {"--pcd-batch", num(pcd_batch)},
      {"--transform",
       [&](const std::string& o, const std::string& v) {
         auto t = parseTransform(o, v);
         if (t)
           c.pcd_world_T_file = *t;
         else
           error = t.error();
         pcd_only = o;
       }},
      {"--max-abs-z",
       [&](const std::string& o, const std::string& v) {
         auto x = number(o, v);
         if (x)
           c.pcd_max_abs_z_m = *x;
         else
           error = x.error();
         pcd_only = o;
       }},
      {"--kitti",
       [&](const std::string& o, const std::string& v) {
         setInput(InputKind::kKitti, o);
         c.kitti.scans_directory = v;
       }},
      {"--kitti-fields",
       [&](const std::string& o, const std::string& v) {
         if (v == "auto")
           c.kitti.fields = KittiFields::kAuto;
         else if (v == "xyz")
           c.kitti.fields = KittiFields::kXyz;
         else if (v == "xyzi")
           c.kitti.fields = KittiFields::kXyzi;
         else
           error = o + ": '" + v + "' is not auto, xyz or xyzi";
       }},
      {"--poses", str(c.kitti.poses_file)},
      {"--scans",
       [&](const std::string&, const std::string& v) {
         auto l = parseIndexList(v);
         if (l)
           c.kitti.scans = *l;
         else
           error = "--scans: " + l.error();
       }},
      {"--kitti-calib", str(c.kitti_calib)},
      {"--bag",
       [&](const std::string& o, const std::string& v) {
         setInput(InputKind::kBag, o);
         c.bag.path = v;
       }},
      {"--cloud-topic", str(c.bag.cloud_topic)},
      {"--pose-topic",
       [&](const std::string&, const std::string& v) {
         c.bag.pose_topic = v;
         pose_topic_given = true;
       }},
      {"--pose-tf",
       [&](const std::string& o, const std::string& v) {
         const size_t comma = v.find(',');
         if (comma == std::string::npos || comma == 0 || comma + 1 == v.size() ||
             v.find(',', comma + 1) != std::string::npos) {
           error = o + " needs PARENT,CHILD (two frame ids), got '" + v + "'";
           return;
         }
         c.bag.pose_tf_parent = v.substr(0, comma);
         c.bag.pose_tf_child = v.substr(comma + 1);
       }},
      {"--extrinsic",
       [&](const std::string& o, const std::string& v) {
         auto t = parseTransform(o, v);
         if (t) {
           c.bag.pose_T_cloud = *t;
           c.bag.has_extrinsic = true;
         } else
           error = t.error();
       }},
      {"--max-pose-gap", num(c.bag.max_pose_gap_s)},
      {"--every", intg(c.bag.every)},
      {"--time-field", str(c.bag.time_field)},
      {"--synthetic-street",
       [&](const std::string& o, const std::string& v) {
         setInput(InputKind::kSynthetic, o);
         auto x = number(o, v);
         if (x)
           c.synthetic.length_m = *x;
         else
           error = x.error();
       }},
      {"--seed", intg(seed)},
      {"--scan-spacing", num(c.synthetic.scan_spacing_m)},
      {"--azimuth-step", num(c.synthetic.azimuth_step_deg)},
      {"--resolution", num(b.geometry.resolution_m)},
      {"--tile-size", intg(b.geometry.tile_size_cells)},
      {"--origin",
       [&](const std::string& o, const std::string& v) {
         auto l = parseNumberList(o, v, 2);
         if (l) {
           b.geometry.origin_x_m = (*l)[0];
           b.geometry.origin_y_m = (*l)[1];
         } else
           error = l.error();
       }},
      {"--k-max", intg(k_max)},
      {"--criterion",
       [&](const std::string& o, const std::string& v) {
         if (v == "icl")
           b.em.criterion = ModelSelection::kIcl;
         else if (v == "bic")
           b.em.criterion = ModelSelection::kBic;
         else
           error = o + ": '" + v + "' is not icl or bic";
       }},
      {"--sigma-floor", num(b.em.sigma_floor_m)},
      {"--blur-sigma", num(b.blur_sigma_m)},
      {"--blur-radius", intg(b.blur_radius_cells)},
      {"--z-bin", num(b.z_bin_m)},
      {"--min-own-points", intg(b.min_own_points)},
      {"--min-range", num(b.min_range_m)},
      {"--max-range", num(b.max_range_m)},
      {"--min-z", num(b.min_z_m)},
      {"--max-z", num(b.max_z_m)},
      {"--voxel", num(b.voxel_m)},
      {"--layer",
       [&](const std::string& o, const std::string& v) {
         if (v == "height")
           b.layer = MapLayer::kHeight;
         else if (v == "reflectivity")
           b.layer = MapLayer::kReflectivity;
         else
           error = o + ": '" + v + "' is not height or reflectivity";
       }},
      {"--ground-height", reflNum(refl.ground_height_m)},
      {"--ground-band",
       [&](const std::string& o, const std::string& v) {
         auto l = parseNumberList(o, v, 2);
         if (l) {
           refl.ground_min_m = (*l)[0];
           refl.ground_max_m = (*l)[1];
         } else
           error = l.error();
         reflectivity_only = o;
       }},
      {"--ground-range", reflNum(refl.max_range_m)},
      {"--reflectivity-scale", reflNum(refl.metres_per_unit)},
      {"--offset",
       [&](const std::string& o, const std::string& v) {
         auto l = parseNumberList(o, v, 3);
         if (l) {
           c.offset_m = Eigen::Vector3d((*l)[0], (*l)[1], (*l)[2]);
           geo.offset_m = c.offset_m;
         } else
           error = l.error();
       }},
      {"--datum", str(geo.datum)},
      {"--utm-zone", str(geo.utm_zone)},
      {"--epsg", str(geo.epsg)},
      {"--mgrs-origin", str(geo.mgrs_origin)},
      {"--georef-origin",
       [&](const std::string& o, const std::string& v) {
         auto l = parseNumberList(o, v, 3);
         if (l)
           geo.georef_origin_m = Eigen::Vector3d((*l)[0], (*l)[1], (*l)[2]);
         else
           error = l.error();
       }},
      {"--threads", intg(b.threads)},
      {"--temp-dir", str(b.temp_directory)},
      {"--spill-buffer-mb", intg(spill_mb)},
  };
  for (int i = 1; i < argc && error.empty(); ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      c.help = true;
      return c;
    } else if (a == "--overwrite") {
      b.overwrite = true;
    } else if (a == "--no-deskew") {
      c.bag.deskew = false;
    } else if (a == "--no-deflate") {
      b.codec.deflate = false;
    } else if (a == "--quiet") {
      c.quiet = true;
    } else if (valued.count(a)) {
      if (i + 1 >= argc) return R::failure(a + " needs a value");
      valued[a](a, argv[++i]);
    } else {
      return R::failure("unknown option '" + a + "' (see --help)");
    }
  }
  if (!error.empty()) return R::failure(error);
  if (c.input == InputKind::kNone)
    return R::failure("no input: give --pcd, --kitti, --bag or --synthetic-street");
  b.em.max_components = k_max;
  c.synthetic.seed = static_cast<uint32_t>(seed);
  if (spill_mb < 1) return R::failure("--spill-buffer-mb must be >= 1");
  b.spill_buffer_bytes = static_cast<size_t>(spill_mb) << 20;
  if (!(pcd_batch >= 1000 && pcd_batch <= 1e8))
    return R::failure("--pcd-batch must be in [1000, 1e8]");
  c.pcd_batch_points = static_cast<size_t>(pcd_batch);
  if (!pcd_only.empty() && c.input != InputKind::kPcd)
    return R::failure(pcd_only + " applies to --pcd input only");
  if (!(c.pcd_max_abs_z_m > 0.0)) return R::failure("--max-abs-z must be > 0");
  const std::string layer_error = checkLayerArgs(c, reflectivity_only);
  if (!layer_error.empty()) return R::failure(layer_error);
  if (c.bag.every < 1) return R::failure("--every must be >= 1");
  if (pose_topic_given && !c.bag.pose_tf_child.empty()) {
    return R::failure("--pose-topic and --pose-tf: give one source of poses");
  }
  if (!(c.bag.max_pose_gap_s > 0.0)) return R::failure("--max-pose-gap must be > 0");
  if (!(c.synthetic.length_m >= 10.0 && c.synthetic.length_m <= 100000.0)) {
    return R::failure("--synthetic-street must be in [10, 100000] m");
  }
  if (!(c.synthetic.scan_spacing_m >= 0.05) || !(c.synthetic.azimuth_step_deg >= 0.05)) {
    return R::failure("--scan-spacing must be >= 0.05 m and --azimuth-step >= 0.05 deg");
  }
  auto georeference = resolveGeoreference(geo);
  if (!georeference) return R::failure(georeference.error());
  b.georeference = *georeference;
  // The map format's bounds, checked here so that a build never ends in a manifest the reader
  // refuses (or a grid of 1e12 cells): one source of truth, checkMapGeometryBounds.
  const double resolution = b.geometry.resolution_m;
  if (!(resolution >= kMinMapResolutionM && resolution <= kMaxMapResolutionM)) {
    return R::failure("--resolution " + text(resolution) + " m is outside the map format's range " +
                      resolutionRange());
  }
  const std::string bounds = checkMapGeometryBounds(b.geometry);
  if (!bounds.empty()) return R::failure("map geometry (--tile-size, --origin): " + bounds);
  const std::string invalid = withLayerOption(b.validate());
  if (!invalid.empty()) return R::failure("invalid options: " + invalid);
  return c;
}

}  // namespace tools
}  // namespace gmm_localization
