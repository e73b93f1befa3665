// evaluate: the paper's experiments (section V) on a localization bag (mode A, LocalizerPipeline
// offline) or on a recording of a real replay (mode B). Usage: evaluate --help.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "common/cli_args.h"
#include "evaluate/evaluate_map_frame.h"
#include "evaluate/evaluate_options.h"
#include "evaluate/evaluate_summary.h"

#ifndef GMM_CONFIG_DIR
#define GMM_CONFIG_DIR "config"
#endif

namespace {

using namespace gmm_localization::eval;

void writeTraversal(const TraversalFigure& f, const std::string& dir, RunInfo& info) {
  if (f.image.rgb.empty()) return;
  writePpm(f.image, dir + "/traversal.ppm");
  std::ofstream j(dir + "/traversal.json");
  j << "{\"width\": " << f.image.width << ", \"height\": " << f.image.height
    << ", \"tile_width\": " << f.image.tile_width << ", \"tile_height\": " << f.image.tile_height
    << ", \"gap\": 3, \"columns\": 11, \"layers\": " << f.layers
    << ", \"heading_step_offset\": " << f.heading_step_offset
    << ", \"heading_step_rad\": " << f.heading_step_rad << ", \"half_x_m\": " << f.half_x_m
    << ", \"evaluations\": " << f.evaluations << ", \"exhaustive_poses\": " << f.exhaustive_poses
    << ", \"search_ms\": " << f.search_ms << ", \"stamp\": " << std::fixed << f.stamp_s << "}\n";
  info.traversal_image = "traversal.ppm";
}

}  // namespace

int main(int argc, char** argv) {
  EvaluateCommand cmd;
  try {
    gmm_localization::tools::NormalizedArgs args(argc, argv);
    cmd = parseEvaluateCommand(args.argc(), args.argv(), GMM_CONFIG_DIR);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "evaluate: %s\n\n%s", e.what(), evaluateUsage());
    return 2;
  }
  if (cmd.mode == EvaluateCommand::Mode::kHelp) {
    std::printf("%s", evaluateUsage());
    return 0;
  }
  try {
    gmm_localization::Result<EvaluationResults> results =
        gmm_localization::Result<EvaluationResults>::failure("not run");
    TraversalFigure traversal;
    std::optional<MapFrame> map_frame;
    if (!cmd.map_poses.empty()) {  // read first: a wrong directory fails before the long run
      auto f = MapFrame::load(cmd.map_poses);
      if (!f) {
        std::fprintf(stderr, "evaluate: %s\n", f.error().c_str());
        return 1;
      }
      map_frame = std::move(*f);
    }
    if (cmd.mode == EvaluateCommand::Mode::kBag) {
      results = runBagEvaluation(cmd.bag, std::cout, &traversal);
    } else {
      results = runRecordedEvaluation(cmd.recorded, std::cout);
    }
    if (!results) {
      std::fprintf(stderr, "evaluate: %s\n", results.error().c_str());
      return 1;
    }
    results->info.world = cmd.world;
    results->info.method = cmd.method;
    results->info.gps = results->info.gps || cmd.gps;
    if (map_frame) {
      results->info.map_poses = cmd.map_poses;
      applyMapFrame(*map_frame, *results);
    }
    const std::string md = writeResults(*results, cmd.out);  // creates the directory
    writeTraversal(traversal, cmd.out, results->info);
    if (!results->info.traversal_image.empty()) writeResults(*results, cmd.out);
    std::printf("\n%s\nwritten to %s/ (summary.md, summary.json, *.csv)\n", md.c_str(),
                cmd.out.c_str());
    const std::string no_data = noDataReason(*results, summarizeResults(*results));
    if (!no_data.empty()) {
      std::fprintf(stderr, "evaluate: %s\n", no_data.c_str());
      return 3;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "evaluate: %s\n", e.what());
    return 1;
  }
  return 0;
}
