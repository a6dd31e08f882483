// The only file that sees VTK (target rtwall_volume_io): reads image data into a VolumeGrid.
#include "volume.h"

#include "scene_files.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkStructuredPoints.h>
#include <vtkStructuredPointsReader.h>
#include <vtkXMLImageDataReader.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <fstream>
#include <mutex>

namespace rtwall {

namespace {

std::shared_ptr<const VolumeGrid> fromImage(vtkImageData* img, const std::string& name) {
    if (!img) throw InputError(name + ": no image data in the file");
    int dims[3];
    img->GetDimensions(dims);
    if (dims[0] < 2 || dims[1] < 2 || dims[2] < 2)
        throw InputError(name + ": the grid must have at least 2 samples on each axis (has " + std::to_string(dims[0]) +
                         "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) + ")");
    if (int64_t(dims[0]) * dims[1] * dims[2] > (int64_t(1) << 30)) throw InputError(name + ": the grid is too large");
    vtkPointData* pd = img->GetPointData();
    vtkDataArray* arr = pd ? pd->GetScalars() : nullptr;
    if (!arr && pd && pd->GetNumberOfArrays() > 0) arr = pd->GetArray(0);
    if (!arr) throw InputError(name + ": no point-data scalars");
    const vtkIdType n = vtkIdType(dims[0]) * dims[1] * dims[2];
    if (arr->GetNumberOfTuples() != n)
        throw InputError(name + ": " + std::to_string(arr->GetNumberOfTuples()) + " values for " + std::to_string(n) +
                         " grid points");
    auto g = std::make_shared<VolumeGrid>();
    g->nx = dims[0];
    g->ny = dims[1];
    g->nz = dims[2];
    g->values.resize(size_t(n));
    g->minValue = INFINITY;
    g->maxValue = -INFINITY;
    for (vtkIdType i = 0; i < n; ++i) {
        const float v = float(arr->GetComponent(i, 0));
        if (!std::isfinite(v)) throw InputError(name + ": value " + std::to_string(i) + " is not finite");
        g->values[size_t(i)] = v;
        g->minValue = std::min(g->minValue, v);
        g->maxValue = std::max(g->maxValue, v);
    }
    return g;
}

}  // namespace

std::shared_ptr<const VolumeGrid> loadVolume(const std::filesystem::path& file) {
    const std::string name = file.string();
    // Parsed from memory whether the bytes come from the disk or from the scene's files (a
    // render client's copy of the master's file), so both give the same grid.
    const std::shared_ptr<const std::vector<uint8_t>> bytes = readSceneFile(name, "volume");
    const std::string text(bytes->begin(), bytes->end());
    // VTK readers print to stderr on errors; turn that off and check the outcome ourselves.
    static std::mutex vtkMutex;  // VTK readers are not documented as thread-safe
    std::lock_guard lock(vtkMutex);
    vtkObject::GlobalWarningDisplayOff();
    const std::string ext = file.extension().string();
    if (ext == ".vti") {
        if (text.find("<VTKFile") == std::string::npos || text.find("ImageData") == std::string::npos)
            throw InputError(name + ": not a VTK XML image data file");
        vtkNew<vtkXMLImageDataReader> reader;
        reader->ReadFromInputStringOn();
        reader->SetInputString(text);
        reader->Update();
        if (reader->GetErrorCode() != 0) throw InputError(name + ": unreadable VTK XML image data");
        return fromImage(reader->GetOutput(), name);
    }
    if (ext == ".vtk") {
        vtkNew<vtkStructuredPointsReader> reader;
        reader->ReadFromInputStringOn();
        reader->SetInputString(text.data(), int(std::min<size_t>(text.size(), size_t(INT_MAX))));
        if (!reader->IsFileStructuredPoints()) throw InputError(name + ": not a legacy VTK structured points file");
        reader->Update();
        if (reader->GetErrorCode() != 0) throw InputError(name + ": unreadable legacy VTK file");
        return fromImage(reader->GetOutput(), name);
    }
    throw InputError(name + ": a volume must be .vti or legacy .vtk structured points");
}

}  // namespace rtwall
