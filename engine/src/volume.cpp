#include "volume.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace rtwall {

float VolumeGrid::sample(float x, float y, float z) const {
    auto axis = [](float c, int n, int& i0, float& f) {
        const float g = std::clamp(c, 0.0f, 1.0f) * float(n - 1);
        i0 = std::min(int(g), n - 2);
        f = g - float(i0);
    };
    int i, j, k;
    float fx, fy, fz;
    axis(x, nx, i, fx);
    axis(y, ny, j, fy);
    axis(z, nz, k, fz);
    auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
    const float c00 = lerp(at(i, j, k), at(i + 1, j, k), fx), c10 = lerp(at(i, j + 1, k), at(i + 1, j + 1, k), fx);
    const float c01 = lerp(at(i, j, k + 1), at(i + 1, j, k + 1), fx);
    const float c11 = lerp(at(i, j + 1, k + 1), at(i + 1, j + 1, k + 1), fx);
    return lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
}

void writeVolumeVti(const std::filesystem::path& file, int nx, int ny, int nz, const std::vector<float>& values) {
    if (nx < 2 || ny < 2 || nz < 2 || values.size() != size_t(nx) * size_t(ny) * size_t(nz))
        throw std::invalid_argument(file.string() + ": a volume needs at least 2 samples per axis and nx*ny*nz values");
    VolumeGrid g;
    g.nx = nx;
    g.ny = ny;
    g.nz = nz;
    g.values = values;
    std::ofstream out(file);
    if (!out) throw InputError(file.string() + ": cannot write");
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        << "  <ImageData WholeExtent=\"0 " << g.nx - 1 << " 0 " << g.ny - 1 << " 0 " << g.nz - 1
        << "\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n"
        << "    <Piece Extent=\"0 " << g.nx - 1 << " 0 " << g.ny - 1 << " 0 " << g.nz - 1 << "\">\n"
        << "      <PointData Scalars=\"density\">\n"
        << "        <DataArray type=\"Float32\" Name=\"density\" format=\"ascii\">\n";
    char buf[32];
    for (size_t i = 0; i < g.values.size(); ++i) {
        std::snprintf(buf, sizeof buf, "%.6g", double(g.values[i]));
        out << buf << ((i % 16 == 15) ? '\n' : ' ');
    }
    out << "\n        </DataArray>\n      </PointData>\n      <CellData/>\n    </Piece>\n  </ImageData>\n</VTKFile>\n";
    if (!out) throw InputError(file.string() + ": write failed");
}

}  // namespace rtwall
