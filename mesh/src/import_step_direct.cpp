// A STEP file's product structure read straight from its entities (cad_tree.h).
//
// OCCT's assembly transfer (STEPControl_ActorRead, under STEPCAFControl_Reader) finds, for every
// NEXT_ASSEMBLY_USAGE_OCCURRENCE, the product behind the occurrence's representation by walking
// every entity that shares that representation: all the other occurrences of the same product.
// N occurrences of one product cost N^2 (201 s of CPU for 140,000 part instances, most of it in
// Interface_Graph::GetSharings). Here one pass over the entities builds the maps the structure
// needs (product definition -> its shape and its occurrences, occurrence -> its placement), the
// placements are computed as OCCT computes them (StepToGeom, the representations' length units,
// gp_Trsf::SetTransformation), and OCCT transfers only the distinct parts, one each. Names and
// colours follow STEPCAFControl_Reader's rules (an occurrence's description, else its name, else
// its id; a product's name, else its id; a part's surface or rendering colour), so the assembly
// is the one XDE gives (tests/engine/step_direct_test.cpp compares the two).
#include "cad_tree.h"

#include "mesh_internal.h"

#include <Interface_Static.hxx>
#include <STEPConstruct_Styles.hxx>
#include <STEPConstruct_UnitContext.hxx>
#include <STEPControl_Reader.hxx>
#include <StepBasic_Product.hxx>
#include <StepBasic_ProductDefinition.hxx>
#include <StepBasic_ProductDefinitionFormation.hxx>
#include <StepBasic_ProductDefinitionWithAssociatedDocuments.hxx>
#include <StepData_GlobalFactors.hxx>
#include <StepData_StepModel.hxx>
#include <StepGeom_Axis2Placement3d.hxx>
#include <StepGeom_GeomRepContextAndGlobUnitAssCtxAndGlobUncertaintyAssCtx.hxx>
#include <StepGeom_GeometricRepresentationContextAndGlobalUnitAssignedContext.hxx>
#include <StepRepr_CharacterizedDefinition.hxx>
#include <StepRepr_GlobalUnitAssignedContext.hxx>
#include <StepRepr_ItemDefinedTransformation.hxx>
#include <StepRepr_MappedItem.hxx>
#include <StepRepr_NextAssemblyUsageOccurrence.hxx>
#include <StepRepr_ProductDefinitionShape.hxx>
#include <StepRepr_PropertyDefinition.hxx>
#include <StepRepr_RepresentationContext.hxx>
#include <StepRepr_RepresentedDefinition.hxx>
#include <StepRepr_ShapeRepresentationRelationshipWithTransformation.hxx>
#include <StepRepr_Transformation.hxx>
#include <StepShape_ContextDependentShapeRepresentation.hxx>
#include <StepShape_ShapeDefinitionRepresentation.hxx>
#include <StepShape_ShapeRepresentation.hxx>
#include <StepToGeom.hxx>
#include <StepVisual_Colour.hxx>
#include <StepVisual_OverRidingStyledItem.hxx>
#include <StepVisual_PresentationStyleByContext.hxx>
#include <StepVisual_StyleContextSelect.hxx>
#include <StepVisual_StyledItem.hxx>
#include <StepVisual_StyledItemTarget.hxx>
#include <TCollection_AsciiString.hxx>
#include <TCollection_ExtendedString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TopLoc_Location.hxx>
#include <TransferBRep.hxx>
#include <Transfer_TransientProcess.hxx>
#include <XSControl_TransferReader.hxx>
#include <XSControl_WorkSession.hxx>
#include <Geom_Axis2Placement.hxx>
#include <Quantity_Color.hxx>
#include <gp_Ax3.hxx>

#include <unordered_map>
#include <unordered_set>

namespace rtwall::detail {
namespace {

using Entity = const Standard_Transient*;

// A name as XDE's document gives it to rtwall: through TCollection_ExtendedString as
// STEPCAFControl_Reader::convertName makes it (decoded as UTF-8 unless the file's code page says
// otherwise), back to UTF-8 as import_cad.cpp's labelName does, so that names are the same
// bytes whichever reader read the file, and valid UTF-8 (StepDirect.NamesOutsideAsciiAreXdesNames).
std::string text(const Handle(TCollection_HAsciiString)& s, bool utf8) {
    if (s.IsNull()) return {};
    return TCollection_AsciiString(TCollection_ExtendedString(s->String(), utf8)).ToCString();
}
bool hasText(const Handle(TCollection_HAsciiString)& s) { return !s.IsNull() && s->UsefullLength() > 0; }

// STEPCAFControl_Reader::ReadNames: a product's name, else its id.
std::string productName(const Handle(StepBasic_ProductDefinition)& pd, bool utf8) {
    const Handle(StepBasic_ProductDefinitionFormation) f = pd->Formation();
    const Handle(StepBasic_Product) p = f.IsNull() ? Handle(StepBasic_Product)() : f->OfProduct();
    if (p.IsNull()) return {};
    return hasText(p->Name()) ? text(p->Name(), utf8) : text(p->Id(), utf8);
}

// An occurrence's description, else its name, else its id.
std::string occurrenceName(const Handle(StepRepr_NextAssemblyUsageOccurrence)& n, bool utf8) {
    if (n->HasDescription() && hasText(n->Description())) return text(n->Description(), utf8);
    if (hasText(n->Name())) return text(n->Name(), utf8);
    return text(n->Id(), utf8);
}

// STEPControl_ActorRead::PrepareUnits: the representation's length and angle units become
// StepToGeom's factors.
void prepareUnits(const Handle(StepRepr_Representation)& rep) {
    Handle(StepRepr_GlobalUnitAssignedContext) units;
    const Handle(StepRepr_RepresentationContext) ctx = rep.IsNull() ? nullptr : rep->ContextOfItems();
    if (const auto a = Handle(StepGeom_GeometricRepresentationContextAndGlobalUnitAssignedContext)::DownCast(ctx); !a.IsNull())
        units = a->GlobalUnitAssignedContext();
    if (const auto b = Handle(StepGeom_GeomRepContextAndGlobUnitAssCtxAndGlobUncertaintyAssCtx)::DownCast(ctx); !b.IsNull())
        units = b->GlobalUnitAssignedContext();
    if (units.IsNull()) {
        StepData_GlobalFactors::Intance().InitializeFactors(1, 1, 1);
        return;
    }
    STEPConstruct_UnitContext unit;
    unit.ComputeFactors(units);
    const int angleMode = Interface_Static::IVal("step.angleunit.mode");
    const double angle = angleMode == 0 ? unit.PlaneAngleFactor() : angleMode == 1 ? 1.0 : M_PI / 180.0;
    StepData_GlobalFactors::Intance().InitializeFactors(unit.LengthFactor(), angle, unit.SolidAngleFactor());
}

class DirectReader {
public:
    DirectReader(STEPControl_Reader& reader, const ProgressFn& progress, CadTree& tree)
        : reader_(reader), progress_(progress), tree_(tree) {}

    bool read(std::string& why, size_t& occurrences) {
        utf8_ = reader_.StepModel()->SourceCodePage() != Resource_FormatType_NoConversion;
        if (!scan(why, occurrences) || !structure(why)) return false;
        transferParts();
        colourParts();
        return true;
    }

private:
    struct Definition {
        Handle(StepBasic_ProductDefinition) pd;
        Handle(StepRepr_Representation) rep;  // its shape representation (via PDS and SDR)
        std::vector<Handle(StepRepr_NextAssemblyUsageOccurrence)> children;
        bool used = false;  // some occurrence places it
        uint32_t product = UINT32_MAX;
    };

    // One pass over the entities: everything the structure needs, keyed by entity. A construct
    // only XDE reads is the refusal (`why`, the first one met); the pass still counts every
    // occurrence, which the caller's warning names.
    bool scan(std::string& why, size_t& occurrenceCount) {
        const Handle(StepData_StepModel) model = reader_.StepModel();
        const Standard_Integer n = model->NbEntities();
        std::vector<Handle(StepRepr_NextAssemblyUsageOccurrence)> occurrences;
        std::vector<Handle(StepShape_ShapeDefinitionRepresentation)> sdrs;
        std::vector<Handle(StepShape_ContextDependentShapeRepresentation)> cdsrs;
        auto refuse = [&](const char* what) {
            if (why.empty()) why = what;
        };
        for (Standard_Integer i = 1; i <= n; ++i) {
            const Handle(Standard_Transient)& e = model->Value(i);
            if (e.IsNull()) continue;
            if (e->IsKind(STANDARD_TYPE(StepBasic_ProductDefinition))) {
                if (e->IsKind(STANDARD_TYPE(StepBasic_ProductDefinitionWithAssociatedDocuments))) {
                    refuse("product definitions with associated documents (external references)");
                    continue;
                }
                defOf_[e.get()] = definitions_.size();
                definitions_.push_back({Handle(StepBasic_ProductDefinition)::DownCast(e), {}, {}, false, UINT32_MAX});
            } else if (e->DynamicType() == STANDARD_TYPE(StepRepr_NextAssemblyUsageOccurrence)) {
                occurrences.push_back(Handle(StepRepr_NextAssemblyUsageOccurrence)::DownCast(e));
            } else if (e->IsKind(STANDARD_TYPE(StepRepr_ProductDefinitionShape))) {
                const auto pds = Handle(StepRepr_ProductDefinitionShape)::DownCast(e);
                const StepRepr_CharacterizedDefinition d = pds->Definition();
                if (const Handle(Standard_Transient) of = d.Value(); !of.IsNull()) shapeOf_.emplace(of.get(), pds);
            } else if (e->IsKind(STANDARD_TYPE(StepShape_ShapeDefinitionRepresentation))) {
                sdrs.push_back(Handle(StepShape_ShapeDefinitionRepresentation)::DownCast(e));
            } else if (e->IsKind(STANDARD_TYPE(StepShape_ContextDependentShapeRepresentation))) {
                cdsrs.push_back(Handle(StepShape_ContextDependentShapeRepresentation)::DownCast(e));
            } else if (e->IsKind(STANDARD_TYPE(StepVisual_StyledItem))) {
                if (e->IsKind(STANDARD_TYPE(StepVisual_OverRidingStyledItem))) {
                    refuse("overriding styles (component colours)");
                    continue;
                }
                const auto style = Handle(StepVisual_StyledItem)::DownCast(e);
                for (Standard_Integer k = 1; k <= style->NbStyles(); ++k) {
                    const auto byContext = Handle(StepVisual_PresentationStyleByContext)::DownCast(style->StylesValue(k));
                    if (!byContext.IsNull() && !byContext->StyleContext().Representation().IsNull()) {
                        refuse("styles in a component's context (component colours)");
                        break;
                    }
                }
                styles_.push_back(style);
            } else if (e->IsKind(STANDARD_TYPE(StepRepr_MappedItem))) {
                refuse("mapped items");
            }
        }
        occurrenceCount = occurrences.size();
        if (!why.empty()) return false;
        // The representation of each product definition's shape (the first, as OCCT's actor
        // would find more than one and make a compound: left to XDE).
        for (const auto& sdr : sdrs) {
            const auto pds = Handle(StepRepr_ProductDefinitionShape)::DownCast(sdr->Definition().PropertyDefinition());
            if (pds.IsNull() || sdr->UsedRepresentation().IsNull()) continue;
            const Handle(StepBasic_ProductDefinition) pd = pds->Definition().ProductDefinition();
            if (pd.IsNull()) continue;
            const auto it = defOf_.find(pd.get());
            if (it == defOf_.end()) continue;
            Definition& d = definitions_[it->second];
            if (!d.rep.IsNull() && d.rep != sdr->UsedRepresentation()) {
                why = "a product with more than one shape representation";
                return false;
            }
            d.rep = sdr->UsedRepresentation();
            repOwner_[d.rep.get()] = pd.get();
        }
        for (const auto& c : cdsrs)
            if (!c->RepresentedProductRelation().IsNull()) placementOf_[c->RepresentedProductRelation().get()] = c;
        for (const auto& o : occurrences) {
            const auto parent = defOf_.find(o->RelatingProductDefinition().get());
            const auto child = defOf_.find(o->RelatedProductDefinition().get());
            if (parent == defOf_.end() || child == defOf_.end()) {
                why = "an occurrence of a product definition not in the file";
                return false;
            }
            definitions_[parent->second].children.push_back(o);
            definitions_[child->second].used = true;
        }
        return true;
    }

    // Products in the file's order; an assembly's components in the order of its occurrences.
    bool structure(std::string& why) {
        for (Definition& d : definitions_) {
            if (d.children.empty() && d.rep.IsNull()) continue;  // no shape: OCCT transfers nothing either
            d.product = uint32_t(tree_.products.size());
            CadProduct p;
            p.name = productName(d.pd, utf8_);
            p.key = "#" + std::to_string(reader_.StepModel()->Number(d.pd));
            p.assembly = !d.children.empty();
            tree_.products.push_back(std::move(p));
            if (!d.children.empty() && !d.rep.IsNull())
                for (Standard_Integer i = 1; i <= d.rep->NbItems(); ++i)
                    if (d.rep->ItemsValue(i).IsNull() || !d.rep->ItemsValue(i)->IsKind(STANDARD_TYPE(StepGeom_Axis2Placement3d))) {
                        why = "an assembly with a shape of its own";
                        return false;
                    }
        }
        for (Definition& d : definitions_) {
            if (d.product == UINT32_MAX) continue;
            if (!d.used) tree_.roots.push_back(d.product);
            CadProduct& p = tree_.products[d.product];
            for (const auto& o : d.children) {
                const Definition& child = definitions_[defOf_.at(o->RelatedProductDefinition().get())];
                if (child.product == UINT32_MAX) continue;  // a product without shape: no component
                CadComponent c;
                c.product = child.product;
                c.name = occurrenceName(o, utf8_);
                if (!placement(o, c.location, why)) return false;
                p.components.push_back(std::move(c));
            }
        }
        if (tree_.roots.empty()) {
            why = "no free product (every product is used by another)";
            return false;
        }
        return true;
    }

    // STEPControl_ActorRead::TransferEntity(NAUO) and ComputeSRRWT, without the searches.
    bool placement(const Handle(StepRepr_NextAssemblyUsageOccurrence)& o, gp_Trsf& trsf, std::string& why) {
        const auto pds = shapeOf_.find(o.get());
        const auto cdsr = pds == shapeOf_.end() ? placementOf_.end() : placementOf_.find(pds->second.get());
        if (cdsr == placementOf_.end() || cdsr->second->RepresentationRelation().IsNull()) {
            why = "an occurrence without a placement";
            return false;
        }
        const Handle(StepRepr_RepresentationRelationship) rr = cdsr->second->RepresentationRelation();
        const Handle(StepRepr_Representation) rep1 = rr->Rep1(), rep2 = rr->Rep2();
        const auto wt = Handle(StepRepr_ShapeRepresentationRelationshipWithTransformation)::DownCast(rr);
        if (rep1.IsNull() || rep2.IsNull() || wt.IsNull()) {
            why = "an occurrence placed without a transformation";
            return false;
        }
        const Handle(StepRepr_ItemDefinedTransformation) idt = wt->TransformationOperator().ItemDefinedTransformation();
        if (idt.IsNull()) {
            why = "a placement by a Cartesian transformation operator";
            return false;
        }
        Handle(StepGeom_Axis2Placement3d) org = Handle(StepGeom_Axis2Placement3d)::DownCast(idt->TransformItem1());
        Handle(StepGeom_Axis2Placement3d) trg = Handle(StepGeom_Axis2Placement3d)::DownCast(idt->TransformItem2());
        if (org.IsNull() || trg.IsNull()) {
            why = "a placement that is not a pair of axis placements";
            return false;
        }
        // Which representation is the child's (CheckSRRReversesNAUO).
        const auto owner = [&](const Handle(StepRepr_Representation)& r) {
            const auto it = repOwner_.find(r.get());
            return it == repOwner_.end() ? nullptr : it->second;
        };
        const Entity parent = o->RelatingProductDefinition().get(), child = o->RelatedProductDefinition().get();
        bool reversed = false;
        if (owner(rep1) == parent && owner(rep2) == child) reversed = true;
        else if (!(owner(rep1) == child && owner(rep2) == parent)) {
            why = "an occurrence whose placement relates other products";
            return false;
        }
        // The axis placements belong to their representations; swapped pairs are mended (as OCCT).
        if (!(holds(rep1, org) && holds(rep2, trg))) {
            if (holds(rep1, trg) && holds(rep2, org)) std::swap(org, trg);
        }
        prepareUnits(rep1);
        const Handle(Geom_Axis2Placement) a = StepToGeom::MakeAxis2Placement(org);
        prepareUnits(rep2);
        const Handle(Geom_Axis2Placement) b = StepToGeom::MakeAxis2Placement(trg);
        if (a.IsNull() || b.IsNull()) {
            why = "an axis placement OCCT cannot read";
            return false;
        }
        trsf.SetTransformation(gp_Ax3(b->Ax2()), gp_Ax3(a->Ax2()));
        if (reversed) trsf.Invert();
        return true;
    }

    // Whether `item` is one of `rep`'s items. An assembly's representation holds one axis
    // placement per component (20,000 under one root in a flat plant): its items go into a set
    // the first time, or the check per occurrence would make the walk quadratic again.
    bool holds(const Handle(StepRepr_Representation)& rep, const Handle(Standard_Transient)& item) {
        auto [it, fresh] = itemsOf_.try_emplace(rep.get());
        if (fresh)
            for (Standard_Integer i = 1; i <= rep->NbItems(); ++i) it->second.insert(rep->ItemsValue(i).get());
        return it->second.count(item.get()) > 0;
    }

    // One OCCT transfer per distinct part; a part's own location moves into its components.
    void transferParts() {
        const Handle(Transfer_TransientProcess) tp = reader_.WS()->TransferReader()->TransientProcess();
        size_t total = 0, done = 0;
        for (const Definition& d : definitions_)
            if (d.product != UINT32_MAX && d.children.empty()) ++total;
        const int rootTrsf = Interface_Static::IVal("read.step.root.transformation");
        std::vector<TopLoc_Location> own(tree_.products.size());
        for (const Definition& d : definitions_) {
            if (d.product == UINT32_MAX || !d.children.empty()) continue;
            // A part placed by occurrences is not a root: its representation's placement is the
            // occurrences' business (STEPControl_ActorRead applies it to roots only).
            Interface_Static::SetIVal("read.step.root.transformation", d.used ? 0 : rootTrsf);
            reader_.TransferEntity(d.pd);
            TopoDS_Shape s = TransferBRep::ShapeResult(tp, d.pd);
            if (d.used) {  // a root part keeps its location, as XDE's free shape does
                own[d.product] = s.Location();
                s.Location(TopLoc_Location());
            }
            tree_.products[d.product].shape = s;
            ++done;
            if (progress_ && !progress_(double(done) / double(std::max<size_t>(total, 1)))) {
                Interface_Static::SetIVal("read.step.root.transformation", rootTrsf);
                throw Cancelled();
            }
        }
        Interface_Static::SetIVal("read.step.root.transformation", rootTrsf);
        for (CadProduct& p : tree_.products)
            for (CadComponent& c : p.components)
                if (!own[c.product].IsIdentity()) c.location = c.location * own[c.product].Transformation();
    }

    // STEPCAFControl_Reader::ReadColors for part-level styles: a style on the part's whole shape
    // gives the part its surface (or rendering) colour, the last such style winning.
    void colourParts() {
        if (styles_.empty()) return;
        std::unordered_map<const TopoDS_TShape*, uint32_t> partOf;
        for (uint32_t i = 0; i < tree_.products.size(); ++i)
            if (!tree_.products[i].shape.IsNull()) partOf.emplace(tree_.products[i].shape.TShape().get(), i);
        const Handle(Transfer_TransientProcess) tp = reader_.WS()->TransferReader()->TransientProcess();
        STEPConstruct_Styles styles(reader_.WS());
        for (const auto& style : styles_) {
            Handle(StepVisual_Colour) surf, bound, curve, render;
            double transparency = 0;
            Standard_Boolean component = false;
            // `component` is true for any style assignment; styles in a component's context were
            // left to XDE by scan().
            if (!styles.GetColors(style, surf, bound, curve, render, transparency, component)) continue;
            if (surf.IsNull() && render.IsNull()) continue;
            const Handle(Standard_Transient) item = style->ItemAP242().Value();
            if (item.IsNull()) continue;
            const TopoDS_Shape s = TransferBRep::ShapeResult(tp, item);
            if (s.IsNull() || !s.Location().IsIdentity()) continue;
            const auto it = partOf.find(s.TShape().get());
            if (it == partOf.end()) continue;
            Quantity_Color c;
            STEPConstruct_Styles::DecodeColor(render.IsNull() ? surf : render, c);
            tree_.products[it->second].colour = std::array<float, 3>{float(c.Red()), float(c.Green()), float(c.Blue())};
        }
    }

    STEPControl_Reader& reader_;
    const ProgressFn& progress_;
    CadTree& tree_;
    bool utf8_ = true;  // the file's strings are UTF-8 (its code page)
    std::vector<Definition> definitions_;
    std::unordered_map<Entity, size_t> defOf_;                                             // product definition -> definitions_
    std::unordered_map<Entity, Handle(StepRepr_ProductDefinitionShape)> shapeOf_;           // PD or NAUO -> its PDS
    std::unordered_map<Entity, Handle(StepShape_ContextDependentShapeRepresentation)> placementOf_;  // PDS -> CDSR
    std::unordered_map<Entity, Entity> repOwner_;                                          // representation -> its PD
    std::unordered_map<Entity, std::unordered_set<Entity>> itemsOf_;                       // representation -> its items (holds)
    std::vector<Handle(StepVisual_StyledItem)> styles_;
};

}  // namespace

bool readStepDirect(STEPControl_Reader& reader, const ProgressFn& progress, CadTree& tree, std::string& why, size_t& occurrences) {
    why.clear();
    occurrences = 0;
    return DirectReader(reader, progress, tree).read(why, occurrences);
}

}  // namespace rtwall::detail
