// Volume data for the volume material: a regular grid of scalars (VTK image data), read by a
// small library that keeps VTK to itself (engine/src/volume_vtk.cpp, target rtwall_volume_io).
#pragma once

#include <rtwall/mesh.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

namespace rtwall {

struct VolumeGrid {
    int nx = 0, ny = 0, nz = 0;  // samples per axis, each >= 2
    std::vector<float> values;   // x fastest
    float minValue = 0, maxValue = 0;

    // Trilinear, at normalised coordinates in [0, 1]^3 (the grid spans the unit cube).
    float sample(float x, float y, float z) const;
    float at(int i, int j, int k) const { return values[(size_t(k) * ny + j) * nx + i]; }
};

// Reads .vti (XML image data) or legacy .vtk structured points; the first point-data array
// (its first component). Throws InputError "file: what".
std::shared_ptr<const VolumeGrid> loadVolume(const std::filesystem::path& file);

}  // namespace rtwall
