// GLX_NV_swap_group on the presenter's windows (swap_group.h).
#include "swap_group.h"

#include <GL/glx.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

// GLFW's native access (glfw3native.h's GLFW_EXPOSE_NATIVE_X11/GLX declarations, exported by
// libglfw 3.3). Declared here because that header also wants the XRandR headers, a development
// package for two declarations.
extern "C" {
Display* glfwGetX11Display(void);
GLXWindow glfwGetGLXWindow(GLFWwindow* window);
}

#include <sstream>

namespace rtwall::detail {

namespace {

// A whole token of the space-separated extension string (GLX_NV_swap_group is a prefix of nothing
// today, but a substring test is how such checks go wrong).
bool hasExtension(const char* extensions, const std::string& name) {
    if (!extensions) return false;
    std::istringstream in(extensions);
    for (std::string token; in >> token;)
        if (token == name) return true;
    return false;
}

}  // namespace

std::string joinSwapGroup(const std::vector<GLFWwindow*>& windows, int group, int barrier) {
    const std::string what = "swap_group = " + std::to_string(group) + (barrier > 0 ? ", swap_barrier = " + std::to_string(barrier) : "");
    Display* display = glfwGetX11Display();
    if (!display) return "GLX_NV_swap_group is absent (not an X11 display): " + what + " not applied; the screens swap on their own";
    const char* extensions = glXQueryExtensionsString(display, DefaultScreen(display));
    if (!hasExtension(extensions, "GLX_NV_swap_group")) {
        const char* vendor = glXGetClientString(display, GLX_VENDOR);
        return std::string("GLX_NV_swap_group is absent (GLX vendor ") + (vendor ? vendor : "unknown") + "): " + what +
               " not applied; the screens swap on their own (and the nodes on the master's barrier)";
    }
    using QueryMax = Bool (*)(Display*, int, GLuint*, GLuint*);
    using Join = Bool (*)(Display*, GLXDrawable, GLuint);
    using Bind = Bool (*)(Display*, GLuint, GLuint);
    const auto queryMax = reinterpret_cast<QueryMax>(glXGetProcAddress(reinterpret_cast<const GLubyte*>("glXQueryMaxSwapGroupsNV")));
    const auto join = reinterpret_cast<Join>(glXGetProcAddress(reinterpret_cast<const GLubyte*>("glXJoinSwapGroupNV")));
    const auto bind = reinterpret_cast<Bind>(glXGetProcAddress(reinterpret_cast<const GLubyte*>("glXBindSwapBarrierNV")));
    if (!queryMax || !join || !bind) return "GLX_NV_swap_group is listed but its functions are missing: " + what + " not applied";
    GLuint maxGroups = 0, maxBarriers = 0;
    if (!queryMax(display, DefaultScreen(display), &maxGroups, &maxBarriers)) return "GLX_NV_swap_group: the driver gives no group limits: " + what + " not applied";
    if (GLuint(group) > maxGroups)
        return "GLX_NV_swap_group: swap_group = " + std::to_string(group) + " exceeds the driver's " + std::to_string(maxGroups) + " group(s): not applied";
    if (barrier > 0 && GLuint(barrier) > maxBarriers)
        return "GLX_NV_swap_group: swap_barrier = " + std::to_string(barrier) + " exceeds the driver's " + std::to_string(maxBarriers) +
               " barrier(s) (a G-Sync/Quadro Sync board gives one): not applied";
    for (GLFWwindow* w : windows) {
        glfwMakeContextCurrent(w);
        if (!join(display, glfwGetGLXWindow(w), GLuint(group))) return "GLX_NV_swap_group: the driver refused to join a window to group " + std::to_string(group);
    }
    if (barrier > 0 && !bind(display, GLuint(group), GLuint(barrier)))
        return "GLX_NV_swap_group: the driver refused to bind group " + std::to_string(group) + " to barrier " + std::to_string(barrier);
    return "GLX_NV_swap_group: " + std::to_string(windows.size()) + " window(s) joined swap group " + std::to_string(group) +
           (barrier > 0 ? ", bound to swap barrier " + std::to_string(barrier) : "");
}

}  // namespace rtwall::detail
