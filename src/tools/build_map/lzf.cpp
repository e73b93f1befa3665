#include "build_map/lzf.h"

#include <cstring>
#include <string>

namespace gmm_localization {
namespace tools {

// liblzf's stream: a control byte c. c < 32: a literal run of c + 1 bytes follows. Else a
// back-reference: length (c >> 5) + 2, with a further length byte added when (c >> 5) == 7,
// and distance ((c & 0x1f) << 8) + next byte + 1 back from the output position. A reference
// may overlap the bytes it produces (run-length encoding), so it is copied byte by byte.
Status lzfDecompress(const uint8_t* in, size_t in_bytes, uint8_t* out, size_t out_bytes) {
  size_t ip = 0, op = 0;
  auto at = [&](const char* what) {
    return Status::failure(std::string("LZF data: ") + what + " at input byte " +
                           std::to_string(ip) + " (output byte " + std::to_string(op) + " of " +
                           std::to_string(out_bytes) + ")");
  };
  while (ip < in_bytes) {
    const size_t ctrl = in[ip++];
    if (ctrl < 32) {
      const size_t n = ctrl + 1;
      if (n > in_bytes - ip) return at("literal run past the end of the input");
      if (n > out_bytes - op) return at("literal run past the expected size");
      std::memcpy(out + op, in + ip, n);
      ip += n;
      op += n;
      continue;
    }
    size_t n = ctrl >> 5;
    if (n == 7) {
      if (ip >= in_bytes) return at("back-reference length past the end of the input");
      n += in[ip++];
    }
    n += 2;
    if (ip >= in_bytes) return at("back-reference distance past the end of the input");
    const size_t distance = ((ctrl & 0x1f) << 8) + in[ip++] + 1;
    if (distance > op) return at("back-reference before the start of the output");
    if (n > out_bytes - op) return at("back-reference past the expected size");
    for (size_t k = 0; k < n; ++k, ++op) out[op] = out[op - distance];
  }
  if (op != out_bytes) return at("data ends before the expected size");
  return Status::success();
}

}  // namespace tools
}  // namespace gmm_localization
