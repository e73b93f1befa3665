// The command-line conventions every tool follows (src/tools/common/cli_args.h, docs/tools.md):
// --help exits 0 with the usage on stdout, an unknown option or a missing value exits 2 naming
// it, `--opt=value` is `--opt value`, a missing input exits 1. Runs the built binaries.
#include "common/cli_args.h"

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#ifndef GMM_TOOLS_DIR
#error "GMM_TOOLS_DIR (the directory of the built tools) must be defined"
#endif

namespace gmm_localization {
namespace tools {
namespace {

struct ToolRun {
  int code = -1;
  std::string out, err;
};

/// Runs `tool args` from the tools' directory, capturing stdout and stderr.
ToolRun run(const std::string& tool, const std::string& args) {
  const std::string base = ::testing::TempDir() + "cli_" + tool;
  const std::string cmd = std::string(GMM_TOOLS_DIR) + "/" + tool + " " + args + " >" + base +
                          ".out 2>" + base + ".err </dev/null";
  ToolRun r;
  const int status = std::system(cmd.c_str());
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const std::string& path) {
    std::string s;
    if (FILE* f = std::fopen(path.c_str(), "rb")) {
      char buf[4096];
      size_t n;
      while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
      std::fclose(f);
    }
    return s;
  };
  r.out = slurp(base + ".out");
  r.err = slurp(base + ".err");
  return r;
}

const char* kTools[] = {"build_map",   "simulate", "evaluate",    "bench_registration",
                        "kitti_check", "map_info", "sim_validate"};

TEST(CliConventions, HelpExitsZeroWithTheUsageOnStdout) {
  for (const char* tool : kTools) {
    const ToolRun r = run(tool, "--help");
    EXPECT_EQ(r.code, kExitOk) << tool << ": " << r.err;
    EXPECT_GT(r.out.size(), 100u) << tool << " prints no usage on stdout";
  }
}

TEST(CliConventions, AnUnknownOptionIsAUsageErrorNamingIt) {
  for (const char* tool : kTools) {
    // evaluate and kitti_check take a mode first.
    const std::string mode = std::string(tool) == "evaluate"      ? "bag "
                             : std::string(tool) == "kitti_check" ? "cells "
                                                                  : "";
    const ToolRun r = run(tool, mode + "--no-such-option 1");
    EXPECT_EQ(r.code, kExitUsage) << tool << ": " << r.err;
    EXPECT_NE((r.err + r.out).find("--no-such-option"), std::string::npos)
        << tool << " does not name the option: " << r.err;
  }
}

TEST(CliConventions, EqualsFormIsTheSameAsTwoWords) {
  // Each pair: the same failing run spelt both ways gives the same exit code and message.
  const std::pair<const char*, const char*> cases[][2] = {
      {{"build_map", "--pcd /nonexistent/a.pcd --output /proc/nonexistent/out"},
       {"build_map", "--pcd=/nonexistent/a.pcd --output=/proc/nonexistent/out"}},
      {{"map_info", "/nonexistent/map --stride 2"}, {"map_info", "/nonexistent/map --stride=2"}},
      {{"evaluate", "bag --bag /nonexistent.bag --map /nonexistent --out /proc/nonexistent/o"},
       {"evaluate", "bag --bag=/nonexistent.bag --map=/nonexistent --out=/proc/nonexistent/o"}},
      {{"kitti_check", "cells --data /nonexistent --work /proc/nonexistent/w"},
       {"kitti_check", "cells --data=/nonexistent --work=/proc/nonexistent/w"}},
  };
  for (const auto& c : cases) {
    const ToolRun a = run(c[0].first, c[0].second);
    const ToolRun b = run(c[1].first, c[1].second);
    EXPECT_EQ(a.code, kExitFailed) << c[0].first << " " << c[0].second << ": " << a.err;
    EXPECT_EQ(b.code, a.code) << c[1].second << ": " << b.err;
    EXPECT_EQ(b.err, a.err) << c[1].first;
    EXPECT_NE(a.err.find("/nonexistent"), std::string::npos)
        << c[0].first << " does not name the missing input: " << a.err;
  }
  // build_map takes the other tools' --out for its --output.
  const ToolRun out = run("build_map", "--pcd /nonexistent/a.pcd --out=/proc/nonexistent/out");
  EXPECT_EQ(out.code, kExitFailed) << out.err;
  EXPECT_EQ(out.err,
            run("build_map", "--pcd /nonexistent/a.pcd --output /proc/nonexistent/out").err);
  // A value after '=' reaches the option: an out-of-range one is refused by name.
  const ToolRun bad = run("map_info", "--stride=0 /nonexistent/map");
  EXPECT_EQ(bad.code, kExitUsage) << bad.err;
}

TEST(CliConventions, MissingValueIsAUsageError) {
  for (const auto& [tool, args] : {std::pair<const char*, const char*>{"build_map", "--pcd"},
                                   {"map_info", "--stride"},
                                   {"simulate", "--seed"},
                                   {"sim_validate", "--revolutions"},
                                   {"bench_registration", "--map"}}) {
    const ToolRun r = run(tool, args);
    EXPECT_EQ(r.code, kExitUsage) << tool << " " << args << ": " << r.err;
  }
}

TEST(NormalizedArgs, SplitsEqualsForms) {
  char a0[] = "tool", a1[] = "--out=dir", a2[] = "--x", a3[] = "v=w",
       a4[] = "--empty=", a5[] = "-k=v", a6[] = "--k=a=b";
  char* argv[] = {a0, a1, a2, a3, a4, a5, a6, nullptr};
  NormalizedArgs n(7, argv);
  ASSERT_EQ(n.argc(), 10);
  const char* expected[] = {"tool",    "--out", "dir",  "--x", "v=w",
                            "--empty", "",      "-k=v", "--k", "a=b"};
  for (int i = 0; i < 10; ++i) EXPECT_STREQ(n.argv()[i], expected[i]) << i;
  EXPECT_EQ(n.argv()[10], nullptr);
}

}  // namespace
}  // namespace tools
}  // namespace gmm_localization
