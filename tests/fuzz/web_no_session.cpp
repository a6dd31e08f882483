// For fuzz_web only: the WallSession methods that WebApi's changes call. The fuzz target's
// backend (rtwall/web_testing.h's FakeConsole) never runs a change, so none of these may ever be
// reached; each stops the run as a finding if one is. (The real ones are the wall library's,
// which the fuzz build does not compile.)
#include <rtwall/wall.h>

#include <cstdio>
#include <cstdlib>

namespace rtwall {

namespace {
[[noreturn]] void ran(const char* what) {
    std::fprintf(stderr, "fuzz_web: a change ran (%s): the fake console must never run one\n", what);
    std::abort();
}
}  // namespace

const SceneDesc& WallSession::scene() const { ran("scene"); }
const PartView& WallSession::partView() const { ran("partView"); }
void WallSession::setPartView(const PartView&) { ran("setPartView"); }
void WallSession::showAllParts() { ran("showAllParts"); }
void WallSession::setSection(uint32_t, const SectionPlane&) { ran("setSection"); }
const std::vector<Bookmark>& WallSession::bookmarks() const { ran("bookmarks"); }
void WallSession::saveBookmark(const std::string&) { ran("saveBookmark"); }
bool WallSession::goToBookmark(const std::string&, double) { ran("goToBookmark"); }
bool WallSession::deleteBookmark(const std::string&) { ran("deleteBookmark"); }
bool WallSession::flyTo(const CameraDesc&, double) { ran("flyTo"); }
const std::vector<Measurement>& WallSession::measurements() const { ran("measurements"); }
std::optional<Measurement> WallSession::measureBetween(double, double, double, double) { ran("measureBetween"); }
bool WallSession::deleteMeasurement(size_t) { ran("deleteMeasurement"); }
void WallSession::restoreSession(const SessionState&) { ran("restoreSession"); }

}  // namespace rtwall
