// `rtwall gen step` / `rtwall gen iges`: a STEP (IGES) assembly with repeated parts, written
// through OpenCASCADE's XDE (STEPCAFControl_Writer, IGESCAFControl_Writer), so the importer
// reads a file that its own code did not write.
//
// Three parts (a plate, a bolt, a bracket), each with a colour and a name, make one "module"
// sub-assembly (a plate, four bolts, two brackets: seven part instances); the root "plant"
// places the module on a square grid, so the file holds each part's geometry once and
// 7 x modules part instances. Sizes in millimetres, z up (as CAD files are).
//
// With --rows, the plant holds one sub-assembly per grid row, and the rows the modules (as large
// CAD assemblies nest): OCCT's STEP reader takes time quadratic in the components of one
// assembly (docs/assemblies.md), so this is how a file of 100,000s of part instances is read.
//
// With --flat (step, iges), nothing is reused: every part of every module is a solid of its own
// whose placement is baked into its geometry, as meshers and flat exports write, plus one
// mirrored bracket: the test data for finding congruent shapes (issue 29).
//
// `rtwall gen step-curved` writes the same layout with curved parts, where the tessellation
// deflections decide what the model looks like (the tessellation benchmark's model): a plate with
// every edge filleted (cylindrical and spherical blends), pins with a filleted head (a torus),
// ball knobs (spheres) and gasket rings (tori): eleven part instances per module.
#include "generators.h"

#include <BRepBuilderAPI_Transform.hxx>
#include <BRep_Tool.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESCAFControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_StepModelType.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_ExtendedString.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Vertex.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Ax2.hxx>
#include <gp_Trsf.hxx>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace rtwall::gen {
namespace {

TopLoc_Location at(double x, double y, double z, double turnDegrees = 0) {
    gp_Trsf r, t;
    r.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), turnDegrees * M_PI / 180.0);
    t.SetTranslation(gp_Vec(x, y, z));
    return TopLoc_Location(t * r);
}

// `shape` with every edge (or, with `onlyAbove`, every edge wholly above that height) rounded to
// `radius`.
TopoDS_Shape filleted(const TopoDS_Shape& shape, double radius, double onlyAbove = -1e300) {
    BRepFilletAPI_MakeFillet fillet(shape);
    TopTools_IndexedMapOfShape edges;
    TopExp::MapShapes(shape, TopAbs_EDGE, edges);
    for (int i = 1; i <= edges.Extent(); ++i) {
        const TopoDS_Edge& e = TopoDS::Edge(edges(i));
        TopoDS_Vertex a, b;
        TopExp::Vertices(e, a, b);
        if (!a.IsNull() && BRep_Tool::Pnt(a).Z() <= onlyAbove) continue;
        if (!b.IsNull() && BRep_Tool::Pnt(b).Z() <= onlyAbove) continue;
        fillet.Add(radius, e);
    }
    fillet.Build();
    if (!fillet.IsDone()) throw std::runtime_error("OpenCASCADE could not fillet a part");
    return fillet.Shape();
}

}  // namespace

namespace {

enum class PartSet { Plain, Curved };

void writeAssembly(const GenOptions& o, bool iges, PartSet set) {
    const bool curved = set == PartSet::Curved;
    if (o.flat && curved) throw std::runtime_error("gen step-curved: --flat is for step and iges");
    const bool flat = o.flat;
    // Part instances wanted; 7 (curved: 11) per module, so modules = ceil(instances / per module).
    const int64_t perModule = curved ? 11 : 7;
    const int64_t wanted = o.instances > 0 ? o.instances : 1000 * perModule;
    const int64_t modules = (wanted + perModule - 1) / perModule;
    const auto side = int64_t(std::ceil(std::sqrt(double(modules))));
    std::filesystem::create_directories(o.out);
    const std::filesystem::path file = o.out / (iges ? "assembly.igs" : "assembly.step");

    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));  // OCCT prints to stdout otherwise
    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    const Handle(XCAFDoc_ColorTool) colours = XCAFDoc_DocumentTool::ColorTool(doc->Main());
    auto part = [&](const TopoDS_Shape& s, const char* name, double r, double g, double b) {
        const TDF_Label l = shapes->AddShape(s, false);
        TDataStd_Name::Set(l, TCollection_ExtendedString(name));
        colours->SetColor(l, Quantity_Color(r, g, b, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
        return l;
    };
    if (flat) {
        // No reuse at all: every part of every module is a free solid, moved into place by
        // copying its geometry (BRepBuilderAPI_Transform), as meshers and flat exports write.
        const TopoDS_Shape plate = BRepPrimAPI_MakeBox(gp_Pnt(-40, -40, 0), 80, 80, 6).Shape();
        const TopoDS_Shape bolt = BRepPrimAPI_MakeCylinder(4, 20).Shape();
        const TopoDS_Shape bracket = BRepPrimAPI_MakeBox(gp_Pnt(-5, -15, 0), 10, 30, 40).Shape();
        auto placed = [](const TopoDS_Shape& s, const TopLoc_Location& module, const TopLoc_Location& local) {
            return BRepBuilderAPI_Transform(s, module.Transformation() * local.Transformation(), true).Shape();
        };
        for (int64_t m = 0; m < modules; ++m) {
            const TopLoc_Location where = at(100.0 * double(m % side), 100.0 * double(m / side), 0, double(m % 4) * 90.0);
            const std::string n = " " + std::to_string(m + 1);
            part(placed(plate, where, at(0, 0, 0)), ("plate" + n).c_str(), 0.55, 0.57, 0.6);
            int k = 0;
            for (double x : {-30.0, 30.0})
                for (double y : {-30.0, 30.0})
                    part(placed(bolt, where, at(x, y, 6)), ("bolt" + n + "." + std::to_string(++k)).c_str(), 0.8, 0.65, 0.2);
            part(placed(bracket, where, at(-20, 0, 6)), ("bracket" + n + ".1").c_str(), 0.15, 0.35, 0.75);
            part(placed(bracket, where, at(20, 0, 6, 180)), ("bracket" + n + ".2").c_str(), 0.15, 0.35, 0.75);
        }
        gp_Trsf mirror;
        mirror.SetMirror(gp_Ax2(gp_Pnt(-60, 0, 0), gp_Dir(1, 0, 0)));  // the plane x = -60
        part(BRepBuilderAPI_Transform(placed(bracket, at(0, 0, 0), at(-20, 0, 6)), mirror, true).Shape(), "bracket mirrored", 0.15,
             0.35, 0.75);
    }

    if (!flat) {
        const TDF_Label module = shapes->NewShape();
        TDataStd_Name::Set(module, "module");
        auto component = [&](const TDF_Label& into, const TDF_Label& what, const TopLoc_Location& loc, const std::string& name) {
            const TDF_Label c = shapes->AddComponent(into, what, loc);
            TDataStd_Name::Set(c, TCollection_ExtendedString(name.c_str()));
        };
        if (!curved) {
            const TDF_Label plate = part(BRepPrimAPI_MakeBox(gp_Pnt(-40, -40, 0), 80, 80, 6).Shape(), "plate", 0.55, 0.57, 0.6);
            const TDF_Label bolt = part(BRepPrimAPI_MakeCylinder(4, 20).Shape(), "bolt", 0.8, 0.65, 0.2);
            const TDF_Label bracket = part(BRepPrimAPI_MakeBox(gp_Pnt(-5, -15, 0), 10, 30, 40).Shape(), "bracket", 0.15, 0.35, 0.75);
            component(module, plate, at(0, 0, 0), "plate");
            int k = 0;
            for (double x : {-30.0, 30.0})
                for (double y : {-30.0, 30.0}) component(module, bolt, at(x, y, 6), "bolt " + std::to_string(++k));
            component(module, bracket, at(-20, 0, 6), "bracket 1");
            component(module, bracket, at(20, 0, 6, 180), "bracket 2");
        } else {
            // A plate rounded on every edge, pins with a rounded head, a ball on each pin, two rings.
            const TDF_Label plate = part(filleted(BRepPrimAPI_MakeBox(gp_Pnt(-40, -40, 0), 80, 80, 8).Shape(), 3.0),
                                         "rounded plate", 0.55, 0.57, 0.6);
            const TDF_Label pin = part(filleted(BRepPrimAPI_MakeCylinder(4, 24).Shape(), 1.5, 12.0), "pin", 0.8, 0.65, 0.2);
            const TDF_Label knob = part(BRepPrimAPI_MakeSphere(7).Shape(), "knob", 0.75, 0.15, 0.12);
            const TDF_Label ring = part(BRepPrimAPI_MakeTorus(14, 3).Shape(), "ring", 0.15, 0.35, 0.75);
            component(module, plate, at(0, 0, 0), "plate");
            int k = 0;
            for (double x : {-25.0, 25.0})
                for (double y : {-25.0, 25.0}) {
                    ++k;
                    component(module, pin, at(x, y, 8), "pin " + std::to_string(k));
                    component(module, knob, at(x, y, 36), "knob " + std::to_string(k));
                }
            component(module, ring, at(0, 0, 11), "ring 1");
            component(module, ring, at(0, 0, 17), "ring 2");
        }

        const TDF_Label plant = shapes->NewShape();
        TDataStd_Name::Set(plant, "plant");
        TDF_Label row;
        for (int64_t m = 0; m < modules; ++m) {
            const double x = 100.0 * double(m % side), y = 100.0 * double(m / side), turn = double(m % 4) * 90.0;
            if (!o.rows) {
                component(plant, module, at(x, y, 0, turn), "module " + std::to_string(m + 1));
                continue;
            }
            // plant > row N (a product of its own, placed at its y) > module M.
            if (m % side == 0) {
                row = shapes->NewShape();
                const std::string name = "row " + std::to_string(m / side + 1);
                TDataStd_Name::Set(row, TCollection_ExtendedString(name.c_str()));
            }
            component(row, module, at(x, 0, 0, turn), "module " + std::to_string(m + 1));
            if (m % side == side - 1 || m == modules - 1) component(plant, row, at(0, y, 0), "row " + std::to_string(m / side + 1));
        }
        shapes->UpdateAssemblies();
    }

    const std::string what = iges ? "gen iges: " : "gen step: ";
    try {
        bool ok = false;
        if (iges) {
            IGESCAFControl_Writer writer;
            writer.SetColorMode(true);
            writer.SetNameMode(true);
            ok = writer.Transfer(doc) && writer.Write(file.c_str());
        } else {
            // The unit is a static of OCCT's, read at the transfer: set for this file, then put back.
            const std::string unitBefore = Interface_Static::CVal("write.step.unit");
            if (!o.stepUnit.empty() && !Interface_Static::SetCVal("write.step.unit", o.stepUnit.c_str()))
                throw std::runtime_error(what + "unknown length unit '" + o.stepUnit + "'");
            STEPCAFControl_Writer writer;
            writer.SetColorMode(true);
            writer.SetNameMode(true);
            const bool transferred = writer.Transfer(doc, STEPControl_AsIs);
            Interface_Static::SetCVal("write.step.unit", unitBefore.c_str());
            if (!transferred) throw std::runtime_error(what + "OpenCASCADE could not transfer the assembly");
            ok = writer.Write(file.c_str()) == IFSelect_RetDone;
        }
        if (!ok) throw std::runtime_error(what + "cannot write " + file.string());
    } catch (const Standard_Failure& e) {
        throw std::runtime_error(what + "OpenCASCADE: " + e.GetMessageString());
    }
    XCAFApp_Application::GetApplication()->Close(doc);
    std::fprintf(stderr, "wrote %s: %lld modules, %lld part instances of %d parts%s\n", file.c_str(), (long long)modules,
                (long long)(perModule * modules), curved ? 4 : 3, flat ? " (flat: each a solid of its own, and a mirrored bracket)" : "");
}

}  // namespace

void genStep(const GenOptions& o) { writeAssembly(o, false, PartSet::Plain); }
void genIges(const GenOptions& o) { writeAssembly(o, true, PartSet::Plain); }
void genStepCurved(const GenOptions& o) { writeAssembly(o, false, PartSet::Curved); }

}  // namespace rtwall::gen
