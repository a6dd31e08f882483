// The re-projection of rtwall/reproject.h on the GPU (issue 27): the same algorithm in GLSL 330
// passes (display/shaders/warp_*), for the GL presenter. Depth-tested point splats, one per
// source pixel, then the two crack passes, the older view splatted the same way, the holes
// filled from it, then from the row's farther known neighbour, then the background colour;
// the debug view's tints; a target at the newest view's own pose copies it. The arithmetic is
// the CPU warp's in float, so the two agree but for points within float rounding of a pixel's
// edge (tests/display/gl_reproject_test.cpp states how closely).
#pragma once

#include <rtwall/display.h>
#include <rtwall/warp.h>

#include <memory>
#include <vector>

namespace rtwall {

// A shader compiled by the current context's driver; InputError (with the driver's log) when
// it does not compile.
unsigned compileShader(unsigned type, const ShaderSource& source);
// A program of two shaders, linked by the current context's driver (InputError with its log).
unsigned linkProgram(const ShaderSource& vertex, const ShaderSource& fragment);
// One of the shipped GL passes (warpShaders()) by file name; std::logic_error for no such file.
ShaderSource warpShader(const std::string& name);

class GlReprojector {
public:
    // Needs a current OpenGL 3.3 core context; its objects live there (and in contexts that
    // share it). Throws InputError when the driver does not compile a warp shader.
    GlReprojector();
    ~GlReprojector();
    GlReprojector(const GlReprojector&) = delete;
    GlReprojector& operator=(const GlReprojector&) = delete;

    // The newest view warped to `target` at the newest view's size, as Reprojector::warp does
    // (`options.threads` aside), in the texture it returns: RGBA8, image row y in texture row y,
    // rgb the warped colour (with `debug`, warpDebugColours' tints), alpha the WarpPixel (its
    // value / 255). The texture is the object's own, overwritten by the next warp. Throws
    // std::invalid_argument when a depth span does not have one value per pixel. Leaves the
    // framebuffer binding at 0.
    unsigned warp(const WarpSource& newest, const CameraDesc& target, const WarpSource* older = nullptr,
                  const WarpOptions& options = {}, bool debug = false);
    unsigned texture() const;
    int width() const;
    int height() const;
    // The last warp read back (tests, comparisons): its colours and each pixel's origin.
    void read(Image& image, std::vector<WarpPixel>* origins = nullptr) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rtwall
