// STEP and IGES assemblies through OpenCASCADE's XDE document (the one OCCT translation unit of
// the importer, so that OCCT's large headers are compiled once).
//
// STEPCAFControl_Reader / IGESCAFControl_Reader transfer the file into a TDocStd_Document whose
// XCAFDoc_ShapeTool holds the assembly structure: free shapes (roots), assemblies whose
// components reference other labels with a location, and simple shapes (the parts). Each part
// label is tessellated once (BRepMesh_IncrementalMesh) into one TriangleMesh; every component
// that references it, however deep, becomes an instance with the product of the locations on
// its path. Names come from TDataStd_Name, colours from XCAFDoc_ColorTool (a component's own
// colour over its part's, over its assembly's).
#include "rtwall/mesh.h"

#include "assembly_import.h"
#include "mesh_internal.h"

#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Message_ProgressScope.hxx>
#include <Poly_Triangulation.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_AsciiString.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDF_Tool.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Trsf.hxx>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <new>
#include <string>

namespace rtwall::detail {
namespace {

namespace fs = std::filesystem;
using Matrix = Affine;

// More instances than this is an input error (as for glTF and scene files).
constexpr uint64_t kMaxInstances = uint64_t(1) << 24;
constexpr uint32_t kNoMesh = UINT32_MAX;  // a part without triangles
// The share of a load's progress that reading and transferring the file takes (tessellating the
// distinct parts, the rest).
constexpr double kTransferShare = 0.9;

[[noreturn]] void fail(const fs::path& file, const std::string& what) { throw InputError(file.string() + ": " + what); }

Matrix toMatrix(const gp_Trsf& t) {
    Matrix m;
    for (int r = 1; r <= 3; ++r)
        for (int c = 1; c <= 4; ++c) m[size_t(4 * (r - 1) + (c - 1))] = t.Value(r, c);
    return m;
}

std::string labelName(const TDF_Label& label) {
    Handle(TDataStd_Name) name;
    if (!label.FindAttribute(TDataStd_Name::GetID(), name)) return {};
    return TCollection_AsciiString(name->Get(), '?').ToCString();
}

std::string labelEntry(const TDF_Label& label) {
    TCollection_AsciiString entry;
    TDF_Tool::Entry(label, entry);
    return entry.ToCString();
}

// The part's faces as one mesh, in the part's own coordinates (the faces' locations applied),
// with per-vertex normals from the triangulation, flipped where a face is reversed.
TriangleMesh tessellate(const TopoDS_Shape& shape, const AssemblyOptions& options) {
    BRepMesh_IncrementalMesh mesher(shape, options.linearDeflection, false, options.angularDeflection, false);
    TriangleMesh mesh;
    std::vector<float> xyz, normals;
    std::vector<uint32_t> tri;
    for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) {
        const TopoDS_Face& face = TopoDS::Face(ex.Current());
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t = BRep_Tool::Triangulation(face, loc);
        if (t.IsNull() || t->NbTriangles() == 0) continue;
        if (!t->HasNormals()) t->ComputeNormals();
        const gp_Trsf trsf = loc.Transformation();
        const bool reversed = face.Orientation() == TopAbs_REVERSED;
        const auto base = uint32_t(xyz.size() / 3);
        for (Standard_Integer i = 1; i <= t->NbNodes(); ++i) {
            const gp_Pnt p = t->Node(i).Transformed(trsf);
            xyz.insert(xyz.end(), {float(p.X()), float(p.Y()), float(p.Z())});
            gp_Dir n = t->Normal(i).Transformed(trsf);
            if (reversed) n.Reverse();
            normals.insert(normals.end(), {float(n.X()), float(n.Y()), float(n.Z())});
        }
        for (Standard_Integer i = 1; i <= t->NbTriangles(); ++i) {
            Standard_Integer a, b, c;
            t->Triangle(i).Get(a, b, c);
            if (reversed) std::swap(b, c);
            tri.insert(tri.end(), {base + uint32_t(a - 1), base + uint32_t(b - 1), base + uint32_t(c - 1)});
        }
    }
    for (float f : xyz)
        if (!std::isfinite(f)) throw InputError("a tessellated vertex is not finite");
    MeshAccess::setVertexCount(mesh, xyz.size() / 3);
    MeshAccess::positions(mesh).assign(std::move(xyz));
    MeshAccess::indices(mesh).assign(std::move(tri));
    if (mesh.vertexCount() > 0) mesh.setNormals(std::move(normals));
    recentre(mesh);
    return mesh;
}

class XdeReader {
public:
    XdeReader(const fs::path& file, const AssemblyOptions& options, const Handle(TDocStd_Document)& doc, Assembly& out)
        : file_(file), options_(options), out_(out) {
        shapes_ = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
        colors_ = XCAFDoc_DocumentTool::ColorTool(doc->Main());
    }

    void read() {
        TDF_LabelSequence roots;
        shapes_->GetFreeShapes(roots);
        if (roots.IsEmpty()) fail(file_, "no shapes in the file");
        // CAD files are z-up; rtwall's cameras are y-up: turn the model -90 degrees about x.
        const Matrix zUp{1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0};
        countParts(roots);
        for (const TDF_Label& r : roots) visit(r, -1, zUp, -1);
    }

private:
    // How many distinct parts there are, for the progress report.
    void countParts(const TDF_LabelSequence& roots) {
        std::vector<TDF_Label> stack(roots.begin(), roots.end());
        std::map<std::string, bool> seen;
        while (!stack.empty()) {
            TDF_Label l = stack.back();
            stack.pop_back();
            if (shapes_->IsReference(l)) {
                TDF_Label ref;
                if (shapes_->GetReferredShape(l, ref)) l = ref;
            }
            if (!seen.emplace(labelEntry(l), true).second) continue;
            if (shapes_->IsAssembly(l)) {
                TDF_LabelSequence comps;
                shapes_->GetComponents(l, comps, false);
                stack.insert(stack.end(), comps.begin(), comps.end());
            } else {
                ++partsTotal_;
            }
        }
    }

    int colourOf(const TDF_Label& label) const {
        Quantity_Color c;
        if (colors_->GetColor(label, XCAFDoc_ColorSurf, c) || colors_->GetColor(label, XCAFDoc_ColorGen, c)) return material(c);
        return -1;
    }

    int material(const Quantity_Color& c) const {
        // Quantity_Color is linear RGB, as AssemblyMaterial's base colour.
        const std::array<float, 3> rgb{float(c.Red()), float(c.Green()), float(c.Blue())};
        auto it = materialOf_.find(rgb);
        if (it != materialOf_.end()) return it->second;
        AssemblyMaterial m;
        char name[32];
        std::snprintf(name, sizeof name, "colour %.3f %.3f %.3f", double(rgb[0]), double(rgb[1]), double(rgb[2]));
        m.name = name;
        m.baseColor = {rgb[0], rgb[1], rgb[2], 1.0f};
        const int id = int(out_.materials.size());
        out_.materials.push_back(m);
        materialOf_[rgb] = id;
        return id;
    }

    uint32_t defaultMaterial() const { return detail::defaultAssemblyMaterial(out_, defaultMaterial_); }

    uint32_t partMesh(const TDF_Label& part) {
        const std::string key = labelEntry(part);
        if (auto it = meshOf_.find(key); it != meshOf_.end()) return it->second;
        TopoDS_Shape shape;
        if (!XCAFDoc_ShapeTool::GetShape(part, shape) || shape.IsNull()) fail(file_, "part " + key + " has no shape");
        TriangleMesh mesh;
        try {
            mesh = tessellate(shape, options_);
        } catch (const InputError& e) {
            fail(file_, "part '" + labelName(part) + "' (" + key + "): " + e.what());
        }
        ++partsDone_;
        if (options_.progress &&
            !options_.progress(kTransferShare + (1.0 - kTransferShare) * double(partsDone_) / double(std::max<size_t>(partsTotal_, 1))))
            throw Cancelled();
        const std::string name = labelName(part);
        if (mesh.triangleCount() == 0) {
            // Wires, points, or faces OCCT could not mesh: nothing to render, no instances.
            out_.warnings.push_back(file_.string() + ": part '" + (name.empty() ? key : name) + "' has no surface to tessellate; skipped");
            meshOf_[key] = kNoMesh;
            return kNoMesh;
        }
        const auto id = uint32_t(out_.meshes.size());
        out_.meshes.push_back(std::make_shared<const TriangleMesh>(std::move(mesh)));
        out_.meshNames.push_back(name.empty() ? "part " + key : name);
        meshOf_[key] = id;
        return id;
    }

    // `label` is a free shape, a component (a reference with a location) or an assembly.
    void visit(const TDF_Label& root, int parentPart, const Matrix& parentWorld, int parentMaterial) {
        struct Item {
            TDF_Label label;
            int parentPart;
            Matrix world;
            int material;
            size_t depth;
        };
        std::vector<Item> stack{{root, parentPart, parentWorld, parentMaterial, 0}};
        while (!stack.empty()) {
            Item it = stack.back();
            stack.pop_back();
            if (it.depth > 64) fail(file_, "assemblies nest more than 64 deep (a cycle?)");
            TDF_Label label = it.label;
            Matrix world = it.world;
            int mat = it.material;
            std::string name = labelName(label);
            if (const int c = colourOf(label); c >= 0) mat = c;
            if (shapes_->IsReference(label)) {
                world = composeAffine(world, toMatrix(XCAFDoc_ShapeTool::GetLocation(label).Transformation()));
                TDF_Label ref;
                if (!shapes_->GetReferredShape(label, ref)) fail(file_, "component " + labelEntry(label) + " refers to nothing");
                if (name.empty()) name = labelName(ref);
                if (const int c = colourOf(ref); c >= 0 && colourOf(label) < 0) mat = c;
                label = ref;
            }
            if (name.empty()) name = (shapes_->IsAssembly(label) ? "assembly " : "part ") + labelEntry(label);
            const auto part = uint32_t(out_.parts.size());
            out_.parts.push_back({name, it.parentPart});
            if (shapes_->IsAssembly(label)) {
                TDF_LabelSequence comps;
                shapes_->GetComponents(label, comps, false);
                for (Standard_Integer i = comps.Length(); i >= 1; --i)
                    stack.push_back({comps.Value(i), int(part), world, mat, it.depth + 1});
                continue;
            }
            if (out_.instances.size() >= kMaxInstances) fail(file_, "more than " + std::to_string(kMaxInstances) + " part instances");
            AssemblyInstance in;
            in.mesh = partMesh(label);
            if (in.mesh == kNoMesh) continue;
            in.material = mat >= 0 ? uint32_t(mat) : defaultMaterial();
            in.part = part;
            const auto& o = out_.meshes[in.mesh]->origin();
            in.transform = composeAffine(world, Matrix{1, 0, 0, o[0], 0, 1, 0, o[1], 0, 0, 1, o[2]});
            // A location out of double range (1.E+400 in a placement) must not reach Embree.
            for (double v : in.transform)
                if (!std::isfinite(v)) fail(file_, "the placement of '" + name + "' is not finite");
            out_.instances.push_back(in);
        }
    }

    const fs::path& file_;
    const AssemblyOptions& options_;
    Assembly& out_;
    Handle(XCAFDoc_ShapeTool) shapes_;
    Handle(XCAFDoc_ColorTool) colors_;
    std::map<std::string, uint32_t> meshOf_;
    mutable std::map<std::array<float, 3>, int> materialOf_;
    mutable int defaultMaterial_ = -1;
    size_t partsTotal_ = 0, partsDone_ = 0;
};

// OCCT's transfer of the file into the document, the slow part of a large assembly, reports
// through a progress indicator: its position is the first `share` of the load's progress, and a
// progress function that returns false makes it a user break, which OCCT's transfer honours.
class TransferProgress : public Message_ProgressIndicator {
public:
    TransferProgress(const ProgressFn& fn, double share) : fn_(fn), share_(share) {}
    bool cancelled() const { return cancelled_; }

protected:
    void Show(const Message_ProgressScope&, const Standard_Boolean) override {
        if (fn_ && !cancelled_ && !fn_(share_ * GetPosition())) cancelled_ = true;
    }
    Standard_Boolean UserBreak() override { return cancelled_; }

private:
    const ProgressFn& fn_;
    double share_;
    std::atomic<bool> cancelled_{false};
};

// OCCT's readers print to its default messenger (stdout); rtwall's output is its own.
void silenceOcct() {
    static std::once_flag once;
    std::call_once(once, [] { Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer)); });
}

}  // namespace

std::mutex& occtMutex() {
    static std::mutex occt;
    return occt;
}

Assembly importCadHere(const fs::path& file, const AssemblyOptions& options, bool lock) {
    if (!(options.linearDeflection > 0) || !(options.angularDeflection > 0))
        fail(file, "tessellation deflections must be positive");
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) fail(file, "cannot open the file");
    silenceOcct();
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    const bool iges = ext == ".iges" || ext == ".igs";
    Assembly out;
    out.format = iges ? "iges" : "step";
    // OCCT's application object and its static tables are shared: one import at a time.
    std::unique_lock<std::mutex> guard(occtMutex(), std::defer_lock);
    if (lock) guard.lock();
    try {
        struct Document {
            Handle(TDocStd_Document) doc;
            Document() { XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc); }
            ~Document() { XCAFApp_Application::GetApplication()->Close(doc); }
        } document;
        Handle(TDocStd_Document)& doc = document.doc;
        bool ok = false;
        const Handle(TransferProgress) progress = new TransferProgress(options.progress, kTransferShare);
        if (iges) {
            IGESCAFControl_Reader reader;
            reader.SetColorMode(true);
            reader.SetNameMode(true);
            if (reader.ReadFile(file.c_str()) != IFSelect_RetDone) fail(file, "not a readable IGES file");
            ok = reader.Transfer(doc, progress->Start());
        } else {
            STEPCAFControl_Reader reader;
            reader.SetColorMode(true);
            reader.SetNameMode(true);
            if (reader.ReadFile(file.c_str()) != IFSelect_RetDone) fail(file, "not a readable STEP file");
            ok = reader.Transfer(doc, progress->Start());
        }
        if (progress->cancelled()) throw Cancelled();
        if (!ok) fail(file, "OpenCASCADE could not transfer the file's shapes");
        XdeReader(file, options, doc, out).read();
    } catch (const Standard_Failure& e) {
        fail(file, std::string("OpenCASCADE: ") + (e.GetMessageString() && *e.GetMessageString() ? e.GetMessageString() : e.DynamicType()->Name()));
    } catch (const std::bad_alloc&) {
        fail(file, "out of memory while reading");
    }
    if (out.instances.empty()) fail(file, "no part with a surface in the file");
    return out;
}

}  // namespace rtwall::detail
