#pragma once
// A node of the branch-and-bound over a SearchProblem (grid_search.cpp, match_certificate.cpp):
// heading, the first translation of its block, its layer and its bound, and the heap order both
// searches pop nodes in. Private to the matching stage.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "gmm_localization/core/matching/grid_search.h"

namespace gmm_localization {
namespace search_detail {

struct Node {
  int64_t bound;
  int32_t heading_index;
  int32_t ty;
  int32_t tx;
  int32_t layer;
};

/// Lexicographic tie key (heading, ty, tx): smaller wins.
inline bool keyLess(int ja, int tya, int txa, int jb, int tyb, int txb) {
  if (ja != jb) return ja < jb;
  if (tya != tyb) return tya < tyb;
  return txa < txb;
}

/// Heap order: higher bound first; on equal bounds the smaller first-leaf key first.
struct Lower {
  bool operator()(const Node& a, const Node& b) const {
    if (a.bound != b.bound) return a.bound < b.bound;
    return keyLess(b.heading_index, b.ty, b.tx, a.heading_index, a.ty, a.tx);
  }
};

/// Orders the records a search keeps for the certificates (SearchOutcome::branched,
/// interval_bounds) by key, as SearchOutcome's lookups expect them.
template <typename Record>
void sortByKey(std::vector<Record>& records) {
  std::sort(records.begin(), records.end(),
            [](const Record& a, const Record& b) { return a.key < b.key; });
}

/// The outcome for leaf (j, tx, ty) with quantized score `score`: its pose and log-likelihood.
SearchOutcome makeOutcome(const SearchProblem& problem, int j, int tx, int ty, int64_t score,
                          SearchStats stats);

}  // namespace search_detail
}  // namespace gmm_localization
