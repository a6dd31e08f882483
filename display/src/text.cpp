// The status overlay's text: a 3x5 pixel font, rendered on the CPU into an image that the GL
// presenter copies onto the first screen (glBlitFramebuffer) and the headless one pastes.
#include <rtwall/display.h>

#include <cctype>
#include <cstring>
#include <sstream>

namespace rtwall {

namespace {

// Rows top to bottom, three columns each ('1' lit).
const char* glyph(char c) {
    switch (c) {
    case '0': return "111101101101111";
    case '1': return "010110010010111";
    case '2': return "111001111100111";
    case '3': return "111001111001111";
    case '4': return "101101111001001";
    case '5': return "111100111001111";
    case '6': return "111100111101111";
    case '7': return "111001001001001";
    case '8': return "111101111101111";
    case '9': return "111101111001111";
    case 'A': return "010101111101101";
    case 'B': return "110101110101110";
    case 'C': return "011100100100011";
    case 'D': return "110101101101110";
    case 'E': return "111100110100111";
    case 'F': return "111100110100100";
    case 'G': return "011100101101011";
    case 'H': return "101101111101101";
    case 'I': return "111010010010111";
    case 'J': return "001001001101010";
    case 'K': return "101101110101101";
    case 'L': return "100100100100111";
    case 'M': return "101111111101101";
    case 'N': return "110101101101101";
    case 'O': return "010101101101010";
    case 'P': return "110101110100100";
    case 'Q': return "010101101110011";
    case 'R': return "110101110101101";
    case 'S': return "011100010001110";
    case 'T': return "111010010010010";
    case 'U': return "101101101101111";
    case 'V': return "101101101101010";
    case 'W': return "101101111111101";
    case 'X': return "101101010101101";
    case 'Y': return "101101010010010";
    case 'Z': return "111001010100111";
    case '.': return "000000000000010";
    case ',': return "000000000010100";
    case ':': return "000010000010000";
    case '%': return "101001010100101";
    case '|': return "010010010010010";
    case '/': return "001001010100100";
    case '-': return "000000111000000";
    case '(': return "001010010010001";
    case ')': return "100010010010100";
    default: return "000000000000000";
    }
}

}  // namespace

Image textImage(const std::string& text, int scale) {
    scale = std::max(1, scale);
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    size_t columns = 0;
    for (const std::string& l : lines) columns = std::max(columns, l.size());
    // Each character is 3 pixels and a gap, each line 5 and a gap, with a 2-pixel border.
    Image img;
    img.width = int((columns * 4 + 3) * size_t(scale));
    img.height = int((lines.size() * 6 + 3) * size_t(scale));
    img.rgb.assign(size_t(img.width) * img.height * 3, 24);
    for (size_t l = 0; l < lines.size(); ++l)
        for (size_t i = 0; i < lines[l].size(); ++i) {
            const char* g = glyph(char(std::toupper(static_cast<unsigned char>(lines[l][i]))));
            for (int row = 0; row < 5; ++row)
                for (int col = 0; col < 3; ++col) {
                    if (g[row * 3 + col] != '1') continue;
                    const int x0 = int((2 + i * 4 + size_t(col)) * size_t(scale)), y0 = int((2 + l * 6 + size_t(row)) * size_t(scale));
                    for (int y = y0; y < y0 + scale; ++y)
                        for (int x = x0; x < x0 + scale; ++x) std::memset(img.pixel(x, y), 235, 3);
                }
        }
    return img;
}

}  // namespace rtwall
