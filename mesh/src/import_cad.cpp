// STEP and IGES assemblies through OpenCASCADE (with import_step_direct.cpp, the two OCCT
// translation units of the importer).
//
// The product structure comes as a CadTree (cad_tree.h): for STEP from rtwall's direct reader
// (import_step_direct.cpp, linear in the part instances) where the file holds nothing only XDE
// reads, else, and for IGES, from OCCT's XDE document (STEPCAFControl_Reader /
// IGESCAFControl_Reader into a TDocStd_Document whose XCAFDoc_ShapeTool holds free shapes,
// assemblies whose components reference other labels with a location, and simple shapes; names
// from TDataStd_Name, colours from XCAFDoc_ColorTool). One walk turns either tree into the
// Assembly: each part tessellated once (BRepMesh_IncrementalMesh) into one TriangleMesh; every
// component that places it, however deep, an instance with the product of the locations on its
// path; a component's colour over its part's, over its assembly's.
#include "rtwall/mesh.h"

#include "assembly_import.h"
#include "cad_tree.h"
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
// The shares of a load's progress: through XDE, reading and transferring the file takes the
// first 0.9 (tessellating the distinct parts, the rest); through the direct STEP reader, reading
// the file the first 0.4, transferring the distinct parts up to 0.6.
constexpr double kTransferShare = 0.9;
constexpr double kDirectReadShare = 0.4, kDirectTransferShare = 0.6;
// Assembly occurrences (NEXT_ASSEMBLY_USAGE_OCCURRENCE entities) from which a STEP file that
// must go through XDE gets a warning saying why: about 1,400 of them (10,000 part instances in
// modules of 7) take XDE 0.76 s against the direct reader's 0.42 s, 10,000 of them 16 s against
// 1.85 s, and the gap grows as the square.
constexpr size_t kSlowXdeOccurrences = 1000;

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
    return TCollection_AsciiString(name->Get()).ToCString();  // UTF-8 (OCCT converts without a replacement character)
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

// XDE's labels as a CadTree: one product per distinct label (a part or an assembly), one
// component per component label.
class XdeTree {
public:
    XdeTree(const fs::path& file, const Handle(TDocStd_Document)& doc, CadTree& tree) : file_(file), tree_(tree) {
        shapes_ = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
        colors_ = XCAFDoc_DocumentTool::ColorTool(doc->Main());
    }

    void read() {
        TDF_LabelSequence roots;
        shapes_->GetFreeShapes(roots);
        if (roots.IsEmpty()) fail(file_, "no shapes in the file");
        for (const TDF_Label& r : roots) tree_.roots.push_back(product(r, 0));
    }

private:
    CadColour colourOf(const TDF_Label& label) const {
        Quantity_Color c;
        if (colors_->GetColor(label, XCAFDoc_ColorSurf, c) || colors_->GetColor(label, XCAFDoc_ColorGen, c))
            return std::array<float, 3>{float(c.Red()), float(c.Green()), float(c.Blue())};
        return std::nullopt;
    }

    uint32_t product(const TDF_Label& label, size_t depth) {
        const std::string key = labelEntry(label);
        if (auto it = index_.find(key); it != index_.end()) return it->second;
        // A cycle makes a component refer to an assembly above it; the walk then stops at 64.
        if (depth > 64) fail(file_, "assemblies nest more than 64 deep (a cycle?)");
        const auto id = uint32_t(tree_.products.size());
        index_[key] = id;
        CadProduct p;
        p.name = labelName(label);
        p.key = key;
        p.colour = colourOf(label);
        p.assembly = shapes_->IsAssembly(label);
        if (!p.assembly && (!XCAFDoc_ShapeTool::GetShape(label, p.shape) || p.shape.IsNull())) fail(file_, "part " + key + " has no shape");
        tree_.products.push_back(std::move(p));
        if (!tree_.products[id].assembly) return id;
        TDF_LabelSequence comps;
        shapes_->GetComponents(label, comps, false);
        for (const TDF_Label& c : comps) {
            TDF_Label ref;
            if (!shapes_->GetReferredShape(c, ref)) fail(file_, "component " + labelEntry(c) + " refers to nothing");
            CadComponent k;
            k.location = XCAFDoc_ShapeTool::GetLocation(c).Transformation();
            k.name = labelName(c);
            k.colour = colourOf(c);
            k.product = product(ref, depth + 1);
            tree_.products[id].components.push_back(std::move(k));
        }
        return id;
    }

    const fs::path& file_;
    CadTree& tree_;
    Handle(XCAFDoc_ShapeTool) shapes_;
    Handle(XCAFDoc_ColorTool) colors_;
    std::map<std::string, uint32_t> index_;
};

// A CadTree as an Assembly: every part tessellated once; every component that places it,
// however deep, an instance with the product of the locations on its path. A component's colour
// over its part's, over its assembly's.
class CadAssembler {
public:
    CadAssembler(const fs::path& file, const AssemblyOptions& options, const CadTree& tree, double progressFrom, Assembly& out)
        : file_(file), options_(options), tree_(tree), from_(progressFrom), out_(out), meshOf_(tree.products.size(), kUnknown) {
        for (const CadProduct& p : tree.products) partsTotal_ += p.assembly ? 0 : 1;
    }

    void build() {
        // CAD files are z-up; rtwall's cameras are y-up: turn the model -90 degrees about x.
        const Matrix zUp{1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0};
        for (uint32_t r : tree_.roots) visit(r, zUp);
    }

private:
    static constexpr uint32_t kUnknown = UINT32_MAX - 1;

    int material(const std::array<float, 3>& rgb) {
        auto it = materialOf_.find(rgb);
        if (it != materialOf_.end()) return it->second;
        AssemblyMaterial m;
        char name[32];
        std::snprintf(name, sizeof name, "colour %.3f %.3f %.3f", double(rgb[0]), double(rgb[1]), double(rgb[2]));
        m.name = name;
        m.baseColor = {rgb[0], rgb[1], rgb[2], 1.0f};  // Quantity_Color is linear RGB, as the base colour
        const int id = int(out_.materials.size());
        out_.materials.push_back(m);
        materialOf_[rgb] = id;
        return id;
    }

    uint32_t partMesh(uint32_t product) {
        if (meshOf_[product] != kUnknown) return meshOf_[product];
        const CadProduct& p = tree_.products[product];
        TriangleMesh mesh;
        try {
            mesh = tessellate(p.shape, options_);
        } catch (const InputError& e) {
            fail(file_, "part '" + p.name + "' (" + p.key + "): " + e.what());
        }
        ++partsDone_;
        if (options_.progress &&
            !options_.progress(from_ + (1.0 - from_) * double(partsDone_) / double(std::max<size_t>(partsTotal_, 1))))
            throw Cancelled();
        if (mesh.triangleCount() == 0) {
            // Wires, points, or faces OCCT could not mesh: nothing to render, no instances.
            out_.warnings.push_back(file_.string() + ": part '" + (p.name.empty() ? p.key : p.name) + "' has no surface to tessellate; skipped");
            return meshOf_[product] = kNoMesh;
        }
        const auto id = uint32_t(out_.meshes.size());
        out_.meshes.push_back(std::make_shared<const TriangleMesh>(std::move(mesh)));
        out_.meshNames.push_back(p.name.empty() ? "part " + p.key : p.name);
        return meshOf_[product] = id;
    }

    void visit(uint32_t root, const Matrix& rootWorld) {
        struct Item {
            uint32_t product;
            const CadComponent* via;  // null for a root
            int parentPart;
            Matrix world;
            int material;
            size_t depth;
        };
        std::vector<Item> stack{{root, nullptr, -1, rootWorld, -1, 0}};
        while (!stack.empty()) {
            Item it = stack.back();
            stack.pop_back();
            if (it.depth > 64) fail(file_, "assemblies nest more than 64 deep (a cycle?)");
            const CadProduct& p = tree_.products[it.product];
            Matrix world = it.world;
            int mat = it.material;
            std::string name;
            if (it.via) {
                name = it.via->name;
                if (it.via->colour) mat = material(*it.via->colour);
                world = composeAffine(world, toMatrix(it.via->location));
                if (name.empty()) name = p.name;
                if (p.colour) {
                    const int c = material(*p.colour);
                    if (!it.via->colour) mat = c;
                }
            } else {
                name = p.name;
                if (p.colour) mat = material(*p.colour);
            }
            if (name.empty()) name = (p.assembly ? "assembly " : "part ") + p.key;
            const auto part = uint32_t(out_.parts.size());
            out_.parts.push_back({name, it.parentPart});
            if (p.assembly) {
                for (size_t i = p.components.size(); i-- > 0;)
                    stack.push_back({p.components[i].product, &p.components[i], int(part), world, mat, it.depth + 1});
                continue;
            }
            if (out_.instances.size() >= kMaxInstances) fail(file_, "more than " + std::to_string(kMaxInstances) + " part instances");
            AssemblyInstance in;
            in.mesh = partMesh(it.product);
            if (in.mesh == kNoMesh) continue;
            in.material = mat >= 0 ? uint32_t(mat) : detail::defaultAssemblyMaterial(out_, defaultMaterial_);
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
    const CadTree& tree_;
    double from_;
    Assembly& out_;
    std::vector<uint32_t> meshOf_;  // per product
    std::map<std::array<float, 3>, int> materialOf_;
    int defaultMaterial_ = -1;
    size_t partsTotal_ = 0, partsDone_ = 0;
};

// OCCT's transfer of the file into the document, the slow part of a large assembly, reports
// through a progress indicator: its position is the first `share` of the load's progress, and a
// progress function that returns false makes it a user break, which OCCT's transfer honours.
class TransferProgress : public Message_ProgressIndicator {
public:
    TransferProgress(const ProgressFn& fn, double from, double to) : fn_(fn), from_(from), share_(to - from) {}
    bool cancelled() const { return cancelled_; }

protected:
    void Show(const Message_ProgressScope&, const Standard_Boolean) override {
        if (fn_ && !cancelled_ && !fn_(from_ + share_ * GetPosition())) cancelled_ = true;
    }
    Standard_Boolean UserBreak() override { return cancelled_; }

private:
    const ProgressFn& fn_;
    double from_, share_;
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
        };
        CadTree tree;
        double tessellationFrom = kTransferShare;
        // XDE's transfer into a document and its labels as the tree, its progress from `from`.
        auto throughXde = [&](auto& reader, double from) {
            Document document;
            const Handle(TransferProgress) progress = new TransferProgress(options.progress, from, kTransferShare);
            const bool ok = reader.Transfer(document.doc, progress->Start());
            if (progress->cancelled()) throw Cancelled();
            if (!ok) fail(file, "OpenCASCADE could not transfer the file's shapes");
            XdeTree(file, document.doc, tree).read();
        };
        if (iges) {
            IGESCAFControl_Reader reader;
            reader.SetColorMode(true);
            reader.SetNameMode(true);
            if (reader.ReadFile(file.c_str()) != IFSelect_RetDone) fail(file, "not a readable IGES file");
            throughXde(reader, 0.0);
            out.reader = "xde";
        } else {
            STEPCAFControl_Reader reader;
            reader.SetColorMode(true);
            reader.SetNameMode(true);
            if (reader.ReadFile(file.c_str()) != IFSelect_RetDone) fail(file, "not a readable STEP file");
            if (options.progress && !options.progress(kDirectReadShare)) throw Cancelled();
            std::string why = "asked for (AssemblyOptions::stepThroughXde)";
            if (!options.stepThroughXde) {
                const ProgressFn parts = [&](double f) {
                    return !options.progress || options.progress(kDirectReadShare + (kDirectTransferShare - kDirectReadShare) * f);
                };
                size_t occurrences = 0;
                if (readStepDirect(reader.ChangeReader(), parts, tree, why, occurrences)) {
                    out.reader = "direct";
                    tessellationFrom = kDirectTransferShare;
                } else if (occurrences >= kSlowXdeOccurrences) {
                    // Where XDE's transfer takes long, say why the file went that way.
                    out.warnings.push_back(file.string() + ": read through OpenCASCADE's XDE document, whose import time grows as the "
                                           "square of its " + std::to_string(occurrences) + " assembly occurrences, because the file has " +
                                           why + " (docs/assemblies.md)");
                }
            }
            if (out.reader.empty()) {
                throughXde(reader, kDirectReadShare);
                out.reader = "xde: " + why;
            }
        }
        CadAssembler(file, options, tree, tessellationFrom, out).build();
    } catch (const Standard_Failure& e) {
        fail(file, std::string("OpenCASCADE: ") + (e.GetMessageString() && *e.GetMessageString() ? e.GetMessageString() : e.DynamicType()->Name()));
    } catch (const std::bad_alloc&) {
        fail(file, "out of memory while reading");
    }
    if (out.instances.empty()) fail(file, "no part with a surface in the file");
    return out;
}

}  // namespace rtwall::detail
