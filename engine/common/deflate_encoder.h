#pragma once
/// Which library writes an archive chunk's deflate stream ([output] deflate_encoder; docs/sweep.md,
/// "Compression"). Both write the zlib format (RFC 1950) that HDF5's deflate filter reads, so every
/// reader opens either archive and reads the same values; only the compressed bytes differ.

#include "engine/common/enum_names.h"

namespace gesweep {

enum class DeflateEncoder {
  kZlib,        ///< zlib's compress2: the bytes HDF5's own filter writes (the default)
  kLibdeflate,  ///< libdeflate: about 2-4 times faster at level 1, within a few % of zlib's size
};
GESWEEP_ENUM_NAMES(DeflateEncoder, {kZlib, "zlib"}, {kLibdeflate, "libdeflate"});

}  // namespace gesweep
