// Shader checks with glslang: every shader the wall uses is compiled as GLSL 330 core before
// the wall starts (and in the tests, where there is no GPU), so a typo is reported with its
// file and line instead of a black screen.
#include <rtwall/display.h>

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>

#include <fstream>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>

namespace rtwall {

namespace {

void initGlslang() {
    static std::once_flag once;
    std::call_once(once, [] { glslang::InitializeProcess(); });
}

// glslang's log ("ERROR: 0:12: 'x' : undeclared identifier") as "<name>:12: 'x' : undeclared identifier".
void collect(const std::string& log, const std::string& name, std::vector<std::string>& out) {
    static const std::regex located(R"(^(ERROR|WARNING): (?:[^:]*):(\d+): (.*)$)");
    std::istringstream in(log);
    std::string line;
    while (std::getline(in, line)) {
        std::smatch m;
        if (std::regex_match(line, m, located)) {
            // glslang ends a failed compile with "'' : compilation terminated": not a problem of its own.
            if (m[1] == "ERROR" && m[3].str().find("compilation terminated") == std::string::npos)
                out.push_back(name + ":" + m[2].str() + ": " + m[3].str());
        } else if (line.starts_with("ERROR: ") && line.find("compilation errors") == std::string::npos &&
                   line.find("Linking") == std::string::npos) {
            out.push_back(name + ": " + line.substr(7));
        }
    }
}

}  // namespace

std::vector<std::string> checkShader(const ShaderSource& source, bool fragment) {
    initGlslang();
    glslang::TShader shader(fragment ? EShLangFragment : EShLangVertex);
    const char* text = source.text.c_str();
    const int length = int(source.text.size());
    const char* name = source.name.c_str();
    shader.setStringsWithLengthsAndNames(&text, &length, &name, 1);
    std::vector<std::string> problems;
    const bool ok = shader.parse(GetDefaultResources(), 330, ECoreProfile, false, false, EShMsgDefault);
    collect(shader.getInfoLog(), source.name, problems);
    if (!ok && problems.empty()) problems.push_back(source.name + ": does not compile: " + shader.getInfoLog());
    if (ok) {
        // Link alone as well: catches a missing main() and unresolved calls.
        glslang::TProgram program;
        program.addShader(&shader);
        if (!program.link(EShMsgDefault)) problems.push_back(source.name + ": does not link: " + program.getInfoLog());
    }
    for (std::string& p : problems)
        while (!p.empty() && (p.back() == '\n' || p.back() == ' ')) p.pop_back();
    return problems;
}

std::vector<std::string> checkWall(const std::filesystem::path& file) { return checkWall(loadWallConfig(file)); }

std::vector<std::string> checkWall(const WallConfig& wall) {
    std::vector<std::string> problems = checkShader(presentVertexShader(), false);
    auto more = [&](std::vector<std::string> p) { problems.insert(problems.end(), p.begin(), p.end()); };
    more(checkShader(presentFragmentShader(), true));
    for (const ShaderSource& s : warpShaders()) more(checkShader(s, s.name.ends_with(".frag")));
    std::set<std::filesystem::path> seen;  // a shader several screens share is reported once
    for (const ScreenConfig& s : wall.screens) {
        if (s.fragmentShader.empty() || !seen.insert(s.fragmentShader).second) continue;
        std::ifstream in(s.fragmentShader, std::ios::binary);
        if (!in) throw InputError(s.fragmentShader.string() + ": cannot be read");
        std::ostringstream text;
        text << in.rdbuf();
        more(checkShader({s.fragmentShader.string(), text.str()}, true));
    }
    more(checkWarp(wall));
    return problems;
}

}  // namespace rtwall
