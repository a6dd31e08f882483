// The operator console's picture of a wall on display nodes on the wire (issue 31, protocol
// version 20): the ask, and the parts of a node's answer with their compressed cells. Cells
// come back exactly; wrong eyes, value widths, rectangles, oversized parts and streams that do
// not decode to their rectangle are refused.
#include "codec.h"
#include "protocol.h"

#include <gtest/gtest.h>

#include <random>

namespace rtwall::cluster {
namespace {

template <class Msg> std::vector<uint8_t> payloadOf(const Msg& msg) {
    const std::vector<uint8_t> bytes = encodeMessage(Header{}, msg);
    return std::vector<uint8_t>(bytes.begin() + kHeaderSize, bytes.end());
}

template <class Msg> std::string refusal(const Msg& m) {
    try {
        const std::vector<uint8_t> p = payloadOf(m);
        decodePayload<Msg>(p.data(), p.size());
    } catch (const DecodeError& e) {
        return e.what();
    }
    return "accepted";
}

NodePreview part(int x0, int y0, int x1, int y1, int valueBytes) {
    std::vector<uint32_t> values(size_t(x1 - x0) * size_t(y1 - y0) * 4, 7);
    NodePreview m{9, 40, 0, 640, 480, x0, y0, x1, y1, uint8_t(valueBytes), false, {}};
    std::vector<uint8_t> scratch;
    if (!values.empty()) encodePreviewCells(values.data(), values.size() / 4, valueBytes, m.cells, scratch);
    return m;
}

TEST(ProtocolPreview, CellsComeBackExactlyInEachValueWidth) {
    std::mt19937 rng(5);
    for (const int bytes : {1, 2, 4}) {
        const uint32_t largest = bytes == 1 ? 0xFF : bytes == 2 ? 0xFFFF : 0xFFFFFFFF;
        EXPECT_EQ(previewValueBytes(largest), bytes);
        std::vector<uint32_t> values(300 * 4);
        for (uint32_t& v : values) v = uint32_t(rng()) & largest;
        std::vector<uint8_t> z, scratch;
        encodePreviewCells(values.data(), 300, bytes, z, scratch);
        std::vector<uint32_t> back(values.size(), 0xDEAD);
        decodePreviewCells(z.data(), z.size(), 300, bytes, back.data(), scratch);
        EXPECT_EQ(back, values) << bytes << " bytes a value";
        // The same stream read as another rectangle or width is refused, not misread.
        EXPECT_THROW(decodePreviewCells(z.data(), z.size(), 299, bytes, back.data(), scratch), DecodeError);
        if (bytes > 1) {
            EXPECT_THROW(decodePreviewCells(z.data(), z.size(), 300, 1, back.data(), scratch), DecodeError);
        }
        z.pop_back();
        EXPECT_THROW(decodePreviewCells(z.data(), z.size(), 300, bytes, back.data(), scratch), DecodeError);
    }
    EXPECT_EQ(previewValueBytes(0x100), 2);
    EXPECT_EQ(previewValueBytes(0x10000), 4);
}

TEST(ProtocolPreview, AsksAndPartsOutOfRangeAreRefusedWithTheirReason) {
    EXPECT_NE(refusal(NodePreviewAsk{1, 320, 0}).find("no display node"), std::string::npos);
    EXPECT_NE(refusal(NodePreviewAsk{1, 0, 1}).find("preview width 0"), std::string::npos);
    EXPECT_NE(refusal(NodePreviewAsk{1, 16385, 1}).find("preview width"), std::string::npos);
    EXPECT_EQ(refusal(NodePreviewAsk{1, 16384, 1}), "accepted");

    EXPECT_EQ(refusal(part(0, 0, 10, 3, 2)), "accepted");
    NodePreview eye = part(0, 0, 10, 3, 2);
    eye.eye = 2;
    EXPECT_NE(refusal(eye).find("preview eye 2"), std::string::npos);
    NodePreview width = part(0, 0, 10, 3, 2);
    width.valueBytes = 3;
    EXPECT_NE(refusal(width).find("values of 3 bytes"), std::string::npos);
    NodePreview backwards = part(0, 0, 10, 3, 1);
    backwards.x0 = 11;
    EXPECT_NE(refusal(backwards).find("preview cell x1"), std::string::npos);
    NodePreview noCells = part(0, 0, 10, 3, 1);
    noCells.cells.clear();
    EXPECT_NE(refusal(noCells).find("do not match"), std::string::npos);
    NodePreview cellsOfNothing = part(0, 0, 0, 0, 1);
    cellsOfNothing.cells = {1, 2, 3};
    EXPECT_NE(refusal(cellsOfNothing).find("do not match"), std::string::npos);
    // A part larger than kMaxPreviewPartBytes: 1024 x 1024 cells of 4-byte values.
    NodePreview huge = part(0, 0, 1, 1, 1);
    huge.x1 = huge.y1 = 1024;
    huge.valueBytes = 4;
    EXPECT_NE(refusal(huge).find("bytes a part"), std::string::npos);
    NodePreview none{9, 0, 0, 0, 0, 0, 0, 0, 0, 1, true, {}};
    EXPECT_EQ(refusal(none), "accepted");  // a node that presented nothing yet
    none.last = false;
    EXPECT_NE(refusal(none).find("cells of no frame"), std::string::npos);
    NodePreview empty = part(0, 0, 2, 2, 1);
    empty.srcWidth = 0;
    EXPECT_NE(refusal(empty).find("empty frame"), std::string::npos);
}

}  // namespace
}  // namespace rtwall::cluster
