#pragma once
// A bounds-checked LZF decompressor (the liblzf format PCL uses for DATA binary_compressed).
// Never reads outside `in` nor writes outside `out`, whatever the input bytes are.

#include <cstddef>
#include <cstdint>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace tools {

/// Decompresses in[0, in_bytes) into out[0, out_bytes). Succeeds only when the input is
/// well-formed and decompresses to exactly out_bytes bytes; else fails with the reason
/// (truncated literal or back-reference, reference before the start, output overflow or
/// shortfall) and the input offset where it was found.
Status lzfDecompress(const uint8_t* in, size_t in_bytes, uint8_t* out, size_t out_bytes);

}  // namespace tools
}  // namespace gmm_localization
