// VTK importers: legacy .vtk (polydata, unstructured grids), XML .vtp and .vtu, and VRML 2.0
// .wrl through vtkVRMLImporter.
//
// VTK parses into its own data set; the triangles are copied once into the TriangleMesh buffers
// that Embree reads, and the VTK objects are destroyed before loadMesh returns, so after the
// import the geometry exists once. Attribute arrays other than point normals and RGB(A) point
// colours are dropped.
//
// VRML: vtkVRMLImporter builds actors in a vtkRenderer. A vtkRenderWindow and vtkRenderer from
// RenderingCore alone (no OpenGL module linked, nothing rendered) are enough to hold them, so the
// import runs headless. Each actor's mapper input is transformed by the actor's matrix in double
// precision, and the actors are appended into one polydata that takes the same path as the
// other formats.
//
// VTK's readers trust header counts (POINTS n allocates n points before reading any), and they
// report problems through a global output window. So the counts are checked against the file
// size first (checkVtkCounts), the window is replaced by one that records the first error, and
// every index VTK hands back is checked here, since VTK does not check connectivity.
#include "import_vtk.h"

#include "mesh_internal.h"
#include "triangulate.h"

#include <vtkActor.h>
#include <vtkActorCollection.h>
#include <vtkAppendPolyData.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDataSetReader.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkLogger.h>
#include <vtkMapper.h>
#include <vtkMatrix4x4.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarsToColors.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkVRMLImporter.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cmath>
#include <limits>
#include <mutex>
#include <new>

namespace rtwall::detail {

using namespace vtkheader;

// ---------------------------------------------------------------------------------------------
// VTK's messages

// Records the first error or warning instead of printing it; VTK writes every reader problem
// here (or to an ErrorEvent observer, which this replaces for objects we do not create).
class RecordingOutputWindow : public vtkOutputWindow {
public:
    static RecordingOutputWindow* New();
    vtkTypeMacro(RecordingOutputWindow, vtkOutputWindow)

    void DisplayText(const char* text) override {
        if (!text) return;
        const auto type = GetCurrentMessageType();
        if (type != MESSAGE_TYPE_ERROR && type != MESSAGE_TYPE_WARNING) return;
        if (first_.empty()) first_ = text;
    }
    void clear() { first_.clear(); }
    // The message without VTK's "ERROR: In /path/file.cxx, line N\nvtkClass (0x...): " prefix,
    // on one printable line.
    std::string message() const {
        std::string m = first_;
        if (const size_t colon = m.find("): "); colon != std::string::npos) m = m.substr(colon + 3);
        for (char& c : m)
            if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = ' ';
        while (!m.empty() && m.back() == ' ') m.pop_back();
        return m.substr(0, 200);
    }
    bool empty() const { return first_.empty(); }

private:
    std::string first_;
};
vtkStandardNewMacro(RecordingOutputWindow);

namespace {

// VTK's output window is global, so VTK imports run one at a time.
std::mutex& vtkMutex() {
    static std::mutex mutex;
    return mutex;
}

class WindowScope {
public:
    WindowScope() : window_(vtkSmartPointer<RecordingOutputWindow>::New()) {
        // VTK 9 also logs every error through vtkLogger straight to stderr; rtwall reports one
        // line itself. Process-wide, and rtwall uses VTK for nothing else.
        static const bool quiet = [] {
            vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
            return true;
        }();
        (void)quiet;
        previous_ = vtkOutputWindow::GetInstance();
        if (previous_) previous_->Register(nullptr);
        vtkOutputWindow::SetInstance(window_);
    }
    ~WindowScope() {
        vtkOutputWindow::SetInstance(previous_);
        if (previous_) previous_->UnRegister(nullptr);
    }
    WindowScope(const WindowScope&) = delete;
    WindowScope& operator=(const WindowScope&) = delete;
    RecordingOutputWindow& window() { return *window_; }

private:
    vtkSmartPointer<RecordingOutputWindow> window_;
    vtkOutputWindow* previous_ = nullptr;
};

// ---------------------------------------------------------------------------------------------
// Data set to triangles

// Reads point i of any VTK point array in double precision, without a virtual call for the
// usual float and double arrays.
class PointReader {
public:
    explicit PointReader(vtkDataArray* a) : array_(a) {
        if (auto* f = vtkFloatArray::SafeDownCast(a)) f_ = f->GetPointer(0);
        if (auto* d = vtkDoubleArray::SafeDownCast(a)) d_ = d->GetPointer(0);
    }
    void get(vtkIdType i, double p[3]) const {
        if (f_) {
            for (int k = 0; k < 3; ++k) p[k] = f_[3 * i + k];
        } else if (d_) {
            for (int k = 0; k < 3; ++k) p[k] = d_[3 * i + k];
        } else {
            array_->GetTuple(i, p);
        }
    }

private:
    vtkDataArray* array_;
    const float* f_ = nullptr;
    const double* d_ = nullptr;
};

// The points' normals, colours and texture coordinates, where the data set has them.
void copyPointAttributes(vtkPolyData* pd, vtkIdType nPoints, const std::string& name, TriangleMesh& mesh) {
    // Point normals are kept when there is one usable normal per point.
    if (vtkDataArray* n = pd->GetPointData() ? pd->GetPointData()->GetNormals() : nullptr;
        n && n->GetNumberOfComponents() == 3 && n->GetNumberOfTuples() == nPoints) {
        std::vector<float> normals(3 * size_t(nPoints));
        bool ok = true;
        for (vtkIdType i = 0; i < nPoints && ok; ++i) {
            double v[3];
            n->GetTuple(i, v);
            const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            ok = std::isfinite(len) && len > 0.0;
            for (int k = 0; k < 3 && ok; ++k) normals[3 * size_t(i) + size_t(k)] = float(v[k] / len);
        }
        if (ok) mesh.setNormals(std::move(normals));
    }

    // Point colours: active point scalars with 3 or 4 components, either unsigned char (0..255)
    // or floating point (0..1, as VTK's colour arrays hold them); alpha is dropped. One-component
    // scalars are data to be mapped through a lookup table, not colours, and are not kept.
    if (vtkDataArray* c = pd->GetPointData() ? pd->GetPointData()->GetScalars() : nullptr;
        c && (c->GetNumberOfComponents() == 3 || c->GetNumberOfComponents() == 4) && c->GetNumberOfTuples() == nPoints) {
        const int type = c->GetDataType();
        const bool bytes = type == VTK_UNSIGNED_CHAR;
        if (bytes || type == VTK_FLOAT || type == VTK_DOUBLE) {
            std::vector<uint8_t> colors(3 * size_t(nPoints));
            for (vtkIdType i = 0; i < nPoints; ++i)
                for (int k = 0; k < 3; ++k) {
                    const double v = c->GetComponent(i, k);
                    const double unit = bytes ? v / 255.0 : v;
                    colors[3 * size_t(i) + size_t(k)] = unit > 0.0 ? uint8_t(std::lround(std::min(unit, 1.0) * 255.0)) : 0;
                }
            mesh.setColors(std::move(colors));
        }
    }

    // Point texture coordinates (TCoords, VRML TextureCoordinate): the first two components of
    // 2- or 3-component coordinates. Like the points, a bad value rejects the file.
    if (vtkDataArray* t = pd->GetPointData() ? pd->GetPointData()->GetTCoords() : nullptr) {
        const int comps = t->GetNumberOfComponents();
        if (comps != 2 && comps != 3)
            fail(name, "point texture coordinates have " + std::to_string(comps) + " components; expected 2 or 3");
        if (t->GetNumberOfTuples() != nPoints)
            fail(name, "UV count mismatch: " + std::to_string(t->GetNumberOfTuples()) + " texture coordinates for " +
                           std::to_string(nPoints) + " points");
        std::vector<float> uv(2 * size_t(nPoints));
        for (vtkIdType i = 0; i < nPoints; ++i)
            for (int k = 0; k < 2; ++k) {
                const double v = t->GetComponent(i, k);
                if (!std::isfinite(v) || std::fabs(v) > double(std::numeric_limits<float>::max()))
                    fail(name, "point " + std::to_string(i) + " has a NaN or infinite texture coordinate");
                uv[2 * size_t(i) + size_t(k)] = float(v);
            }
        mesh.setUVs(std::move(uv));
    }
}

TriangleMesh toTriangles(vtkPolyData* pd, const std::string& name, ImportReport& report) {
    vtkPoints* points = pd->GetPoints();
    const vtkIdType nPoints = points ? points->GetNumberOfPoints() : 0;
    if (nPoints <= 0) fail(name, "contains no points");
    if (uint64_t(nPoints) >= std::numeric_limits<uint32_t>::max()) fail(name, "more points than 32-bit indices can address");
    vtkDataArray* coords = points->GetData();
    if (!coords || coords->GetNumberOfComponents() != 3) fail(name, "points do not have 3 components");

    // Bounds in double precision, then the origin the float buffers are relative to.
    const PointReader pr(coords);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (vtkIdType i = 0; i < nPoints; ++i) {
        double p[3];
        pr.get(i, p);
        for (int k = 0; k < 3; ++k) {
            if (!std::isfinite(p[k]) || std::fabs(p[k]) > 1e30)
                fail(name, "point " + std::to_string(i) + " has a NaN, infinite or out-of-range coordinate");
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    }
    const std::array<double, 3> origin = chooseOrigin(lo, hi);

    vtkCellArray* polys = pd->GetPolys();
    vtkCellArray* strips = pd->GetStrips();
    size_t triangles = 0;
    if (polys) triangles += size_t(std::max<vtkIdType>(0, polys->GetNumberOfConnectivityIds() - 2 * polys->GetNumberOfCells()));
    if (strips) triangles += size_t(std::max<vtkIdType>(0, strips->GetNumberOfConnectivityIds() - 2 * strips->GetNumberOfCells()));

    TriangleMesh mesh;
    mesh.reserve(size_t(nPoints), triangles);
    for (vtkIdType i = 0; i < nPoints; ++i) {
        double p[3];
        pr.get(i, p);
        mesh.addVertex({float(p[0] - origin[0]), float(p[1] - origin[1]), float(p[2] - origin[2])});
    }
    mesh.setOrigin(origin);

    auto checkIds = [&](const char* what, vtkIdType cell, vtkIdType n, const vtkIdType* ids) {
        for (vtkIdType k = 0; k < n; ++k)
            if (ids[k] < 0 || ids[k] >= nPoints)
                fail(name, std::string(what) + " " + std::to_string(cell) + ": point index " + std::to_string(ids[k]) +
                               " is out of range (the file has " + std::to_string(nPoints) + " points)");
    };
    if (polys) {
        auto it = vtkSmartPointer<vtkCellArrayIterator>::Take(polys->NewIterator());
        PolygonTriangulator triangulator;
        std::vector<uint32_t> polygon;
        vtkIdType cell = 0;
        for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++cell) {
            vtkIdType n = 0;
            const vtkIdType* ids = nullptr;
            it->GetCurrentCell(n, ids);
            if (n < 3) fail(name, "polygon " + std::to_string(cell) + " has fewer than 3 corners");
            checkIds("polygon", cell, n, ids);
            polygon.assign(ids, ids + n);
            countPolygon(report, triangulator.triangulate(mesh.positions(), polygon.data(), polygon.size()));
            const std::vector<uint32_t>& t = triangulator.triangles();
            for (size_t k = 0; k + 2 < t.size(); k += 3) {
                if (zeroArea(mesh, t[k], t[k + 1], t[k + 2])) ++report.degenerateTriangles;
                mesh.addTriangle(t[k], t[k + 1], t[k + 2]);
            }
        }
    }
    if (strips) {
        auto it = vtkSmartPointer<vtkCellArrayIterator>::Take(strips->NewIterator());
        vtkIdType cell = 0;
        for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++cell) {
            vtkIdType n = 0;
            const vtkIdType* ids = nullptr;
            it->GetCurrentCell(n, ids);
            if (n < 3) fail(name, "triangle strip " + std::to_string(cell) + " has fewer than 3 points");
            checkIds("triangle strip", cell, n, ids);
            ++report.stripsTriangulated;
            for (vtkIdType k = 0; k + 2 < n; ++k) {
                // Every second triangle of a strip is wound the other way round.
                auto a = uint32_t(ids[k]), b = uint32_t(ids[k + 1]);
                const auto c = uint32_t(ids[k + 2]);
                if (k & 1) std::swap(a, b);
                if (zeroArea(mesh, a, b, c)) ++report.degenerateTriangles;
                mesh.addTriangle(a, b, c);
            }
        }
    }
    report.cellsSkipped += size_t((pd->GetVerts() ? pd->GetVerts()->GetNumberOfCells() : 0) +
                                  (pd->GetLines() ? pd->GetLines()->GetNumberOfCells() : 0));
    if (mesh.triangleCount() == 0) fail(name, "contains no triangles (no polygons or triangle strips)");

    copyPointAttributes(pd, nPoints, name, mesh);
    return mesh;
}

template <class Algorithm>
void runVtk(Algorithm* algorithm, RecordingOutputWindow& window, const std::string& name);

// VRML: one polydata in world coordinates from the importer's actors. Each actor's points are
// transformed by its matrix in double precision (the actor's own points are float), normals by
// the inverse transpose, and each point gets the colour VTK would draw it with: the Color node's
// entry through the mapper's lookup table where the mapper shows scalars, else the actor's
// diffuse colour. Colours are kept when any actor has a Color node or a Material colour;
// normals when every actor has them (vtkAppendPolyData keeps only arrays all inputs have).
vtkSmartPointer<vtkPolyData> vrmlWorld(vtkRenderer* renderer, RecordingOutputWindow& window, const std::string& name) {
    struct Part {
        vtkPolyData* pd;
        vtkActor* actor;
        vtkMapper* mapper;
        bool scalarColors;
    };
    std::vector<Part> parts;
    bool anyColor = false;
    vtkActorCollection* actors = renderer->GetActors();
    vtkCollectionSimpleIterator it;
    actors->InitTraversal(it);
    while (vtkActor* actor = actors->GetNextActor(it)) {
        vtkMapper* mapper = actor->GetMapper();
        auto* pd = vtkPolyData::SafeDownCast(mapper ? mapper->GetInputAsDataSet() : nullptr);
        if (!pd || !pd->GetPoints() || pd->GetNumberOfPoints() == 0) continue;
        vtkDataArray* s = pd->GetPointData()->GetScalars();
        const bool scalarColors = mapper->GetScalarVisibility() && s && mapper->GetLookupTable() &&
                                  s->GetNumberOfComponents() == 1 && s->GetNumberOfTuples() >= pd->GetNumberOfPoints();
        const double* d = actor->GetProperty()->GetDiffuseColor();
        anyColor = anyColor || scalarColors || d[0] != 1.0 || d[1] != 1.0 || d[2] != 1.0;
        parts.push_back({pd, actor, mapper, scalarColors});
    }
    if (parts.empty()) fail(name, "VRML: contains no shapes with geometry");

    auto append = vtkSmartPointer<vtkAppendPolyData>::New();
    append->SetOutputPointsPrecision(vtkAlgorithm::DOUBLE_PRECISION);
    for (const Part& part : parts) {
        vtkPolyData* in = part.pd;
        const vtkIdType n = in->GetNumberOfPoints();
        double m[16];
        vtkMatrix4x4::DeepCopy(m, part.actor->GetMatrix());
        double inv[16];
        vtkMatrix4x4::Invert(m, inv);  // a singular matrix leaves zeros: normals are then dropped below

        auto points = vtkSmartPointer<vtkPoints>::New();
        points->SetDataTypeToDouble();
        points->SetNumberOfPoints(n);
        for (vtkIdType i = 0; i < n; ++i) {
            double p[3];
            in->GetPoint(i, p);
            double q[3];
            for (int r = 0; r < 3; ++r) q[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
            points->SetPoint(i, q);
        }
        auto out = vtkSmartPointer<vtkPolyData>::New();
        out->SetPoints(points);
        out->SetPolys(in->GetPolys());
        out->SetStrips(in->GetStrips());
        out->SetLines(in->GetLines());
        out->SetVerts(in->GetVerts());

        if (vtkDataArray* nin = in->GetPointData()->GetNormals(); nin && nin->GetNumberOfComponents() == 3 && nin->GetNumberOfTuples() == n) {
            auto normals = vtkSmartPointer<vtkDoubleArray>::New();
            normals->SetNumberOfComponents(3);
            normals->SetNumberOfTuples(n);
            for (vtkIdType i = 0; i < n; ++i) {
                double v[3], w[3];
                nin->GetTuple(i, v);
                // Inverse transpose: column r of the inverse.
                for (int r = 0; r < 3; ++r) w[r] = inv[r] * v[0] + inv[4 + r] * v[1] + inv[8 + r] * v[2];
                normals->SetTuple(i, w);
            }
            out->GetPointData()->SetNormals(normals);
        }
        // Texture coordinates pass through unchanged (kept by the append only where every shape has them).
        if (vtkDataArray* tin = in->GetPointData()->GetTCoords(); tin && tin->GetNumberOfTuples() == n)
            out->GetPointData()->SetTCoords(tin);
        if (anyColor) {
            auto colors = vtkSmartPointer<vtkUnsignedCharArray>::New();
            colors->SetNumberOfComponents(3);
            colors->SetNumberOfTuples(n);
            const double* diffuse = part.actor->GetProperty()->GetDiffuseColor();
            vtkDataArray* s = in->GetPointData()->GetScalars();
            vtkScalarsToColors* lut = part.mapper->GetLookupTable();
            for (vtkIdType i = 0; i < n; ++i) {
                double rgb[3] = {diffuse[0], diffuse[1], diffuse[2]};
                if (part.scalarColors) lut->GetColor(s->GetComponent(i, 0), rgb);
                for (int k = 0; k < 3; ++k) {
                    const double v = std::isfinite(rgb[k]) ? std::clamp(rgb[k], 0.0, 1.0) : 0.0;
                    colors->SetComponent(i, k, std::round(v * 255.0));
                }
            }
            out->GetPointData()->SetScalars(colors);
        }
        append->AddInputData(out);  // holds a reference
    }
    runVtk(append.Get(), window, name);
    vtkSmartPointer<vtkPolyData> merged = append->GetOutput();
    return merged;
}

// Runs a reader (and the surface filter for unstructured grids), turning VTK's recorded
// messages into one InputError.
template <class Algorithm>
void runVtk(Algorithm* algorithm, RecordingOutputWindow& window, const std::string& name) {
    window.clear();
    algorithm->Update();
    if (!window.empty()) fail(name, "VTK: " + window.message());
    if (algorithm->GetErrorCode() != 0) fail(name, "VTK could not read the file (error code " + std::to_string(algorithm->GetErrorCode()) + ")");
}

vtkSmartPointer<vtkPolyData> surfaceOf(vtkDataSet* ds, RecordingOutputWindow& window, const std::string& name) {
    if (auto* pd = vtkPolyData::SafeDownCast(ds)) return pd;
    auto filter = vtkSmartPointer<vtkDataSetSurfaceFilter>::New();
    filter->SetInputData(ds);
    runVtk(filter.Get(), window, name);
    vtkSmartPointer<vtkPolyData> out = filter->GetOutput();
    return out;
}

}  // namespace

namespace {

struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
};

// Points this process's stderr at `fd` for the object's lifetime, whatever leaves the scope.
class StderrTo {
public:
    explicit StderrTo(int fd) {
        std::fflush(stderr);
        saved_ = ::dup(2);
        if (saved_ >= 0 && ::dup2(fd, 2) < 0) {
            ::close(saved_);
            saved_ = -1;
        }
    }
    ~StderrTo() {
        if (saved_ < 0) return;
        std::fflush(stderr);
        ::dup2(saved_, 2);
        ::close(saved_);
    }
    StderrTo(const StderrTo&) = delete;
    StderrTo& operator=(const StderrTo&) = delete;
    bool ok() const { return saved_ >= 0; }

private:
    int saved_ = -1;
};

// The first error line VTK's VRML parser printed into `fd`, on one printable line; empty if none.
std::string vrmlParseError(int fd) {
    std::string text;
    char buf[4096];
    for (off_t at = 0; text.size() < 65536;) {
        const ssize_t n = ::pread(fd, buf, sizeof buf, at);
        if (n <= 0) break;
        text.append(buf, size_t(n));
        at += n;
    }
    for (size_t pos = 0; pos < text.size();) {
        const size_t end = std::min(text.find('\n', pos), text.size());
        std::string line = text.substr(pos, end - pos);
        if (line.rfind("Error", 0) == 0) {
            for (char& c : line)
                if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
            return line.substr(0, 200);
        }
        pos = end + 1;
    }
    return {};
}

TriangleMesh loadVtkHere(VtkKind kind, const std::string& data, const std::string& name, ImportReport& report) {
    const std::lock_guard<std::mutex> lock(vtkMutex());
    WindowScope scope;
    RecordingOutputWindow& window = scope.window();
    try {
        if (kind == VtkKind::Legacy) {
            report.format = "vtk";
            // Legacy headers: the type line decides what VTK builds; only two are surfaces.
            const std::string_view d(data);
            size_t pos = 0;
            for (int line = 0; line < 3 && pos != std::string_view::npos; ++line) {
                pos = d.find('\n', pos);
                if (pos != std::string_view::npos) ++pos;
            }
            if (pos == std::string_view::npos) fail(name, "legacy VTK header is incomplete (expected a DATASET line on line 4)");
            const std::string_view fmt = lineAt(d, d.rfind('\n', pos - 2) + 1);
            if (!startsWith(fmt, "ASCII") && !startsWith(fmt, "BINARY")) fail(name + ":line 3", "expected ASCII or BINARY");
            const std::vector<std::string_view> t = tokens(lineAt(d, pos));
            if (t.size() != 2 || t[0] != "DATASET") fail(name + ":line 4", "expected 'DATASET POLYDATA' or 'DATASET UNSTRUCTURED_GRID'");
            if (t[1] != "POLYDATA" && t[1] != "UNSTRUCTURED_GRID")
                fail(name + ":line 4", "DATASET " + std::string(t[1].substr(0, 40)) + " is not supported (POLYDATA and UNSTRUCTURED_GRID are)");
            if (data.size() > size_t(std::numeric_limits<int>::max())) fail(name, "legacy VTK files over 2 GiB are not supported; use .vtp");
            auto reader = vtkSmartPointer<vtkDataSetReader>::New();
            reader->ReadFromInputStringOn();
            reader->SetInputString(data.data(), int(data.size()));
            reader->ReadAllNormalsOn();
            runVtk(reader.Get(), window, name);
            vtkDataSet* ds = reader->GetOutput();
            if (!ds) fail(name, "VTK read no data set");
            vtkSmartPointer<vtkPolyData> pd = surfaceOf(ds, window, name);
            return toTriangles(pd, name, report);
        }
        if (kind == VtkKind::Vrml) {
            report.format = "wrl";
            // vtkVRMLImporter reads only from a named file: the validated bytes go to an
            // anonymous in-memory file, read through its /proc path.
            const int fd = ::memfd_create("rtwall-vrml", MFD_CLOEXEC);
            if (fd < 0) fail(name, std::string("cannot hand the file to VTK: ") + std::strerror(errno));
            Closer closer{fd};
            if (!writeAll(fd, data.data(), data.size()))
                fail(name, std::string("cannot hand the file to VTK: ") + std::strerror(errno));
            auto window3d = vtkSmartPointer<vtkRenderWindow>::New();  // never rendered: holds the renderer
            auto renderer = vtkSmartPointer<vtkRenderer>::New();
            window3d->AddRenderer(renderer);
            auto importer = vtkSmartPointer<vtkVRMLImporter>::New();
            importer->SetFileName(("/proc/self/fd/" + std::to_string(fd)).c_str());
            importer->SetRenderWindow(window3d);
            window.clear();
            // VTK's VRML parser (lex/yacc) reports syntax errors by printing "Error near line N:
            // ..." to stderr and keeps what it parsed so far, so a truncated file would load in
            // part. Its stderr is captured while it runs (VTK imports run one at a time, and in a
            // child process by default) and any error there rejects the file.
            const int errFd = ::memfd_create("rtwall-vrml-errors", MFD_CLOEXEC);
            if (errFd < 0) fail(name, std::string("cannot capture VTK's messages: ") + std::strerror(errno));
            Closer errCloser{errFd};
            {
                const StderrTo capture(errFd);
                if (!capture.ok()) fail(name, std::string("cannot capture VTK's messages: ") + std::strerror(errno));
                importer->Read();
            }
            if (const std::string parseError = vrmlParseError(errFd); !parseError.empty()) {
                // "Error near line 8: parse error" -> FILE:line 8: VRML parse error
                unsigned line = 0;
                if (std::sscanf(parseError.c_str(), "Error near line %u", &line) == 1) {
                    const size_t colon = parseError.find(": ");
                    fail(name + ":line " + std::to_string(line),
                         "VRML: " + (colon == std::string::npos ? parseError : parseError.substr(colon + 2)));
                }
                fail(name, "VRML: " + parseError);
            }
            if (!window.empty()) fail(name, "VTK: " + window.message());
            vtkSmartPointer<vtkPolyData> pd = vrmlWorld(renderer, window, name);
            return toTriangles(pd, name, report);
        }
        if (kind == VtkKind::XmlPolyData) {
            report.format = "vtp";
            auto reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
            reader->ReadFromInputStringOn();
            reader->SetInputString(data);
            runVtk(reader.Get(), window, name);
            vtkPolyData* pd = reader->GetOutput();
            if (!pd) fail(name, "VTK read no data set");
            return toTriangles(pd, name, report);
        }
        report.format = "vtu";
        auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
        reader->ReadFromInputStringOn();
        reader->SetInputString(data);
        runVtk(reader.Get(), window, name);
        vtkUnstructuredGrid* ug = reader->GetOutput();
        if (!ug) fail(name, "VTK read no data set");
        vtkSmartPointer<vtkPolyData> pd = surfaceOf(ug, window, name);
        return toTriangles(pd, name, report);
    } catch (const std::bad_alloc&) {
        fail(name, "out of memory while reading");
    }
}

}  // namespace

// VTK's readers crash on some malformed files (a fuzzer finds a NULL dereference in the legacy
// reader and a division by zero in the XML decompressor within a minute), and a crash or a hang
// must not take rtwall down. So VTK parses in a child process: it hands the mesh back as cache
// bytes in a memfd (decoded and validated here like any cache), or an error line through a
// pipe; a crash, or no answer within the time limit, is reported as a bad file. The child's
// copy disappears with it, so the geometry still exists once afterwards.
TriangleMesh loadVtk(VtkKind kind, const std::string& data, const std::string& name, ImportReport& report) {
    checkVtkCounts(kind, data, name);
    if (const char* inProcess = std::getenv("RTWALL_VTK_IN_PROCESS"); inProcess && *inProcess == '1')
        return loadVtkHere(kind, data, name, report);

    const int memfd = ::memfd_create("rtwall-vtk-mesh", MFD_CLOEXEC);
    int errPipe[2];
    if (memfd < 0 || ::pipe2(errPipe, O_CLOEXEC) != 0) {
        if (memfd >= 0) ::close(memfd);
        fail(name, std::string("cannot start the VTK reader: ") + std::strerror(errno));
    }
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) {
        ::close(memfd);
        ::close(errPipe[0]);
        ::close(errPipe[1]);
        fail(name, std::string("cannot start the VTK reader: ") + std::strerror(errno));
    }
    if (pid == 0) {
        ::close(errPipe[0]);
        dropInheritedCrashHandlers();
        int code = 4;
        try {
            ImportReport r;
            const TriangleMesh mesh = loadVtkHere(kind, data, name, r);
            const std::vector<unsigned char> bytes = encodeMeshCache(mesh, r, 0, 0);
            code = writeAll(memfd, bytes.data(), bytes.size()) ? 0 : 5;
        } catch (const InputError& e) {
            const std::string what = e.what();
            writeAll(errPipe[1], what.data(), what.size());
            code = 3;
        } catch (...) {
        }
        ::_exit(code);
    }
    ::close(errPipe[1]);
    // The error line (small), then the exit status, within a limit that grows with the file:
    // 10 s and 1 s per 2 MB (VTK's ASCII XML reads tens of MB a second). It was 60 s whatever
    // the size, until the CI's fuzz smoke run found a 1.4 KB .vtu on which VTK's reader spins
    // (the input was lost with the throwaway system it was found in): a file that small must
    // not hold the wall for a minute.
    std::string message;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10 + data.size() / (2 << 20));
    int status = 0;
    bool exited = false;
    char buf[512];
    while (!exited) {
        pollfd pfd{errPipe[0], POLLIN, 0};
        if (::poll(&pfd, 1, 50) > 0) {
            const ssize_t n = ::read(errPipe[0], buf, sizeof buf);
            if (n > 0 && message.size() < 4096) message.append(buf, size_t(n));
        }
        const pid_t w = ::waitpid(pid, &status, WNOHANG);
        if (w == pid) exited = true;
        else if (std::chrono::steady_clock::now() > deadline) {
            ::kill(pid, SIGKILL);
            ::waitpid(pid, &status, 0);
            ::close(errPipe[0]);
            ::close(memfd);
            fail(name, "VTK did not finish reading the file within the time limit");
        }
    }
    for (ssize_t n; (n = ::read(errPipe[0], buf, sizeof buf)) > 0 && message.size() < 4096;) message.append(buf, size_t(n));
    ::close(errPipe[0]);
    Closer closer{memfd};
    if (WIFSIGNALED(status)) fail(name, "VTK crashed reading the file (signal " + std::to_string(WTERMSIG(status)) + "); the file is malformed");
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == 3 && !message.empty()) {
        if (const size_t nl = message.find('\n'); nl != std::string::npos) message.resize(nl);
        throw InputError(message);
    }
    if (code != 0) fail(name, "VTK failed reading the file (the reader exited with status " + std::to_string(code) + ")");
    struct stat st {};
    if (::fstat(memfd, &st) != 0 || st.st_size <= 0) fail(name, "the VTK reader returned no mesh");
    void* map = ::mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, memfd, 0);
    if (map == MAP_FAILED) fail(name, "cannot map the mesh the VTK reader returned");
    // The mesh's arrays stay where the child wrote them (a view of the memfd's pages), so the
    // parent never makes its own copy; the mapping goes with the last array that uses it.
    const size_t length = size_t(st.st_size);
    const std::shared_ptr<const void> keep(map, [length](const void* p) { ::munmap(const_cast<void*>(p), length); });
    return decodeMeshCache(static_cast<const unsigned char*>(map), length, 0, 0, name, &report, keep);
}

}  // namespace rtwall::detail
