// fuzz_protocol's input layout: the first byte picks the decoder (its value modulo kSelectors),
// the rest is that decoder's input. make_protocol_corpus writes its seeds with the same numbers,
// so that the two cannot disagree about which decoder a seed is for.
#pragma once

#include "protocol.h"

namespace rtwall::cluster::fuzz {

inline constexpr unsigned kWholeMessage = 0;             // decodeHeader, then the payload decoder its type names
inline constexpr unsigned kFirstPayload = 1;             // 1..kMaxMsgType: decodePayload for MsgType(n)
inline constexpr unsigned kMesh = kMaxMsgType + 1;       // decodeMesh
inline constexpr unsigned kTile = kMesh + 1;             // + TileCodec: decodeTile (4 codecs)
inline constexpr unsigned kWideTile = kTile + 4;         // decodeWideTile: + 0 LZ4, + 1 zstd
inline constexpr unsigned kFeatureTile = kWideTile + 2;  // decodeFeatureTile: the features in the third byte's low bits
inline constexpr unsigned kSelectors = kFeatureTile + 1;

}  // namespace rtwall::cluster::fuzz
