// loadMesh: OpenMesh's format readers feeding rtwall::TriangleMesh directly.
//
// The readers talk to a BaseImporter; ours writes straight into the TriangleMesh buffers, so no
// OpenMesh mesh (and no second copy of the geometry) is ever built. Every file first passes
// validateMesh (validate.cpp), which is what makes the readers safe to run on it; the importer
// still checks every index it is handed, because that is the last line between a file and an
// out-of-bounds read in Embree.
#include "rtwall/mesh.h"

#include "import_vtk.h"
#include "mesh_importer.h"
#include "mesh_internal.h"
#include "triangulate.h"
#include "validate.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/OBJReader.hh>
#include <OpenMesh/Core/IO/reader/OFFReader.hh>
#include <OpenMesh/Core/IO/reader/OMReader.hh>
#include <OpenMesh/Core/IO/reader/PLYReader.hh>
#include <OpenMesh/Core/IO/reader/STLReader.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <new>
#include <optional>
#include <sstream>
#include <streambuf>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace rtwall {
namespace {

namespace fs = std::filesystem;
namespace OmIo = OpenMesh::IO;
using detail::MeshFormat;
using detail::MeshImporter;

// -----------------------------------------------------------------------------------------------
// OpenMesh plumbing

// A read-only, seekable stream over the validated buffer: the readers seek (OBJ reads twice,
// PLY re-reads its header) and the buffer is not copied.
class BufferStreamBuf final : public std::streambuf {
public:
    explicit BufferStreamBuf(std::string& data) { setg(data.data(), data.data(), data.data() + data.size()); }

protected:
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
        if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
        const off_type size = egptr() - eback();
        off_type target = off;
        if (dir == std::ios_base::cur) target += gptr() - eback();
        if (dir == std::ios_base::end) target += size;
        if (target < 0 || target > size) return pos_type(off_type(-1));
        setg(eback(), eback() + target, egptr());
        return pos_type(target);
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
        return seekoff(off_type(pos), std::ios_base::beg, which);
    }
};

// OpenMesh reports through its global omerr/omlog streams. While a file is read they go to a
// string instead of the terminal, so the user sees our one-line error and not the reader's.
//
// omerr's connect() allocates a target that disconnect() forgets without freeing, so connecting
// a buffer per import (and reconnecting std::cerr after it) leaked two targets a file. Instead
// one sink is connected once for the process: it writes to the import's buffer while a capture
// is open and to std::cerr (where omerr went before) otherwise. Captures run under
// openMeshMutex().
class OpenMeshErrSink {
public:
    static OpenMeshErrSink& instance() {
        static OpenMeshErrSink* sink = [] {
            auto* s = new OpenMeshErrSink;  // lives as long as omerr, which keeps a reference
            s->toCerr_ = omerr().disconnect(std::cerr);
            omerr().connect(*s);
            return s;
        }();
        return *sink;
    }
    void capture(std::ostringstream* text) { text_ = text; }
    friend OpenMeshErrSink& operator<<(OpenMeshErrSink& s, const std::string& line) {
        if (s.text_) *s.text_ << line;
        else if (s.toCerr_) std::cerr << line;
        return s;
    }

private:
    std::ostringstream* text_ = nullptr;
    bool toCerr_ = false;
};

class CaptureOpenMeshLog {
public:
    CaptureOpenMeshLog() {
        OpenMeshErrSink::instance().capture(&text_);
        errEnabled_ = omerr().is_enabled();
        omerr().enable();
        logEnabled_ = omlog().is_enabled();
        outEnabled_ = omout().is_enabled();
        omlog().disable();
        omout().disable();
    }
    ~CaptureOpenMeshLog() {
        omerr().flush();
        OpenMeshErrSink::instance().capture(nullptr);
        // Set both ways: a reader that switched it off and then threw leaves it off.
        if (errEnabled_)
            omerr().enable();
        else
            omerr().disable();
        if (logEnabled_) omlog().enable();
        if (outEnabled_) omout().enable();
    }
    CaptureOpenMeshLog(const CaptureOpenMeshLog&) = delete;
    CaptureOpenMeshLog& operator=(const CaptureOpenMeshLog&) = delete;

    // The first line the reader wrote, for an error message. Readers echo bytes of the file,
    // so anything unprintable is replaced.
    std::string firstLine() {
        omerr().flush();
        std::string line;
        std::istringstream in(text_.str());
        while (std::getline(in, line) && line.find_first_not_of(" \t\r") == std::string::npos) {
        }
        for (char& c : line)
            if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
        return line.substr(0, 200);
    }

private:
    std::ostringstream text_;
    bool errEnabled_ = true, logEnabled_ = true, outEnabled_ = true;
};

// The readers are process-wide singletons with per-file state, and the log streams are global.
std::mutex& openMeshMutex() {
    static std::mutex mutex;
    return mutex;
}

// Names each reader's singleton, so that a static OpenMesh build links and registers them all,
// and confirms they are there: without them IOManager would fail every file the same way.
void requireReaders() {
    static const bool registered = [] {
        OmIo::OBJReader();
        OmIo::OFFReader();
        OmIo::PLYReader();
        OmIo::STLReader();
        OmIo::OMReader();
        // can_read() would sniff a file named dummy.<ext>; the filter list names every
        // registered reader's extensions without touching the disk.
        const std::string& filters = OmIo::IOManager().qt_read_filters();
        for (const char* ext : {"*.obj ", "*.off ", "*.ply ", "*.stl ", "*.om "})
            if (filters.find(ext) == std::string::npos) return false;
        return true;
    }();
    if (!registered) throw std::logic_error("rtwall: OpenMesh's mesh readers are not registered");
}

// -----------------------------------------------------------------------------------------------
// Files

struct FormatInfo {
    MeshFormat format;
    const char* name;
};

FormatInfo formatFromExtension(const fs::path& file, const std::string& name) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".obj") return {MeshFormat::Obj, "obj"};
    if (ext == ".off") return {MeshFormat::Off, "off"};
    if (ext == ".ply") return {MeshFormat::Ply, "ply"};
    if (ext == ".stl") return {MeshFormat::Stl, "stl"};
    if (ext == ".om") return {MeshFormat::Om, "om"};
    throw InputError(name + ": unknown mesh format " + (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
                     "; expected .obj, .off, .ply, .stl, .om, .vtk, .vtp, .vtu or .wrl");
}

bool isVtkExtension(const fs::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".vtk" || ext == ".vtp" || ext == ".vtu" || ext == ".wrl";
}

void requireRegularFile(const fs::path& file, const std::string& name) {
    std::error_code ec;
    const fs::file_status st = fs::status(file, ec);
    if (ec && ec != std::errc::no_such_file_or_directory) throw InputError(name + ": cannot access: " + ec.message());
    if (!fs::exists(st)) throw InputError(name + ": no such file");
    if (fs::is_directory(st)) throw InputError(name + ": is a directory, not a mesh file");
    // Devices and pipes have no size to check against and may never end.
    if (!fs::is_regular_file(st)) throw InputError(name + ": not a regular file");
}

std::string readFile(const fs::path& file, const std::string& name) {
    std::error_code ec;
    const uintmax_t size = fs::file_size(file, ec);
    if (ec) throw InputError(name + ": cannot read: " + ec.message());
    if (size == 0) throw InputError(name + ": file is empty");

    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(name + ": cannot open: " + std::error_code(errno, std::generic_category()).message());
    std::string data;
    try {
        data.resize(size_t(size));
    } catch (const std::exception&) {
        throw InputError(name + ": file too large to load (" + std::to_string(size) + " bytes)");
    }
    in.read(data.data(), std::streamsize(size));
    if (size_t(in.gcount()) != size)
        throw InputError(name + ": read only " + std::to_string(in.gcount()) + " of " + std::to_string(size) + " bytes");
    return data;
}

std::string readPrefix(const fs::path& file, size_t bytes) {
    std::ifstream in(file, std::ios::binary);
    std::string prefix(bytes, '\0');
    in.read(prefix.data(), std::streamsize(bytes));
    prefix.resize(size_t(std::max<std::streamsize>(in.gcount(), 0)));
    return prefix;
}

std::string firstToken(const std::string& text) {
    const size_t end = text.find_first_of(" \t\r\n#");
    return text.substr(0, end);
}

TriangleMesh importOpenMesh(const fs::path& file, const FormatInfo& format, std::string& data,
                            const std::string& name, ImportReport* report) {
    const detail::Prepass pre = detail::validateMesh(format.format, data, name);
    requireReaders();

    TriangleMesh mesh;
    // The pre-pass counts are backed by data; the cap (every vertex and triangle takes some
    // bytes of the file) only guards this promise against a slip in a validator.
    mesh.reserve(std::min(pre.vertices, data.size() / 4), std::min(pre.triangles, data.size()));
    MeshImporter importer(mesh, format.format == MeshFormat::Obj);
    importer.restoreRepeatedCorners(&pre.repeatedCorners);
    bool ok = false;
    std::string readerMessage;
    {
        const std::lock_guard<std::mutex> lock(openMeshMutex());
        CaptureOpenMeshLog log;
        BufferStreamBuf buffer(data);
        std::istream in(&buffer);
        OmIo::Options options = OmIo::Options::VertexNormal;
        options += OmIo::Options::VertexColor;
        options += OmIo::Options::VertexTexCoord;
        if (pre.binaryStl) options += OmIo::Options::Binary;
        try {
            // The OFF reader takes its header flags (normals, colours, binary) from sniffing a
            // file by name, a step IOManager skips for streams; without it the flags would be
            // whatever the last OFF file read in this process had. So the file itself is sniffed,
            // and must still start as the validated buffer does.
            if (format.format == MeshFormat::Off) {
                if (!OmIo::OFFReader().can_u_read(name)) throw InputError(name + ": OpenMesh does not recognise the OFF header");
                if (firstToken(readPrefix(file, 256)) != firstToken(data))
                    throw InputError(name + ": the file changed while it was being read");
            }
            ok = OmIo::IOManager().read(in, format.name, importer, options);
        } catch (const InputError&) {
            throw;
        } catch (const std::bad_alloc&) {
            throw InputError(name + ": out of memory while reading");
        } catch (const std::exception& e) {
            throw InputError(name + ": OpenMesh failed: " + e.what());
        }
        if (!ok) readerMessage = log.firstLine();
    }
    if (!importer.error().empty()) throw InputError(name + ": " + importer.error());
    if (!ok)
        throw InputError(name + ": OpenMesh could not read the file" + (readerMessage.empty() ? "" : " (" + readerMessage + ")"));
    importer.resolveHalfedgeFaces();
    if (!importer.error().empty()) throw InputError(name + ": " + importer.error());
    if (mesh.triangleCount() == 0) throw InputError(name + ": contains no triangles");
    importer.finishNormals();
    importer.finishColors();
    importer.finishUVs();
    if (!importer.error().empty()) throw InputError(name + ": " + importer.error());
    // The reserve above follows the pre-pass, which counts STL corners before they are merged
    // into shared vertices (about six times too many): spare capacity would stay resident for
    // as long as the mesh is rendered.
    mesh.shrinkToFit();

    if (report) {
        report->format = format.name;
        importer.reportPolygons(*report);
        report->warnings = pre.warnings;
        report->degenerateTriangles = importer.degenerateTriangles() + pre.droppedDegenerate;
        report->seamVerticesSplit = importer.seamVerticesSplit();
    }
    for (const std::string& warning : pre.warnings) std::cerr << "warning: " + warning + "\n";
    detail::recentre(mesh);
    return mesh;
}

}  // namespace

namespace detail {

// One entry for every format: VTK files are recognised by their bytes, the rest by extension.
TriangleMesh importMesh(const fs::path& file, ImportReport* report) {
    const std::string name = file.string();
    requireRegularFile(file, name);
    const bool vtkExt = isVtkExtension(file);
    std::optional<FormatInfo> format;
    std::string unknownFormat;
    if (!vtkExt) {
        try {
            format = formatFromExtension(file, name);
        } catch (const InputError& e) {
            unknownFormat = e.what();  // unless the content says VTK
        }
    }
    std::string data = readFile(file, name);
    const VtkKind kind = sniffVtk(data);
    if (kind != VtkKind::None) {
        ImportReport local;
        TriangleMesh mesh = loadVtk(kind, data, name, report ? *report : local);
        return mesh;
    }
    if (vtkExt)
        throw InputError(name + (data.rfind("#VRML V1.0", 0) == 0
                                     ? std::string(": VRML 1.0 is not supported (VTK reads VRML 2.0, '#VRML V2.0 utf8')")
                                     : std::string(": not a VTK file (expected '# vtk DataFile Version', an XML <VTKFile> of type PolyData or UnstructuredGrid, or '#VRML V2.0')")));
    if (!format) throw InputError(unknownFormat);
    return importOpenMesh(file, *format, data, name, report);
}

}  // namespace detail

}  // namespace rtwall
