#pragma once
// What every command-line tool of the package shares (docs/tools.md): the exit codes and the
// option spellings.
//   exit 0  done (also --help, which prints the usage on stdout)
//   exit 1  the work failed (an input missing or unreadable, a build or an evaluation failing)
//   exit 2  usage error (an unknown option, a missing or malformed value), with a message
//           naming the option on stderr
// Options take their value as the next argument or after '=': `--out DIR` = `--out=DIR`.

#include <string>
#include <vector>

namespace gmm_localization {
namespace tools {

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitUsage = 2;

/// argv with every "--name=value" split into "--name" "value" (a lone "-" or a value that does
/// not start with "--" is left alone; "--name=" gives an empty value). The strings live as long
/// as this object.
class NormalizedArgs {
 public:
  NormalizedArgs(int argc, char** argv) {
    for (int i = 0; i < argc; ++i) {
      const std::string a = argv[i];
      const size_t eq = a.find('=');
      if (i > 0 && a.rfind("--", 0) == 0 && eq != std::string::npos && eq > 2) {
        words_.push_back(a.substr(0, eq));
        words_.push_back(a.substr(eq + 1));
      } else {
        words_.push_back(a);
      }
    }
    for (std::string& w : words_) pointers_.push_back(&w[0]);
    pointers_.push_back(nullptr);
  }
  NormalizedArgs(const NormalizedArgs&) = delete;
  NormalizedArgs& operator=(const NormalizedArgs&) = delete;

  int argc() const { return static_cast<int>(words_.size()); }
  char** argv() { return pointers_.data(); }

 private:
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

}  // namespace tools
}  // namespace gmm_localization
