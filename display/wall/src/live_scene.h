// The one scene state of a running wall: what every client holds. Every change goes through
// here: the master sends it as a differential update (and checks it first: a bad index or an
// unreadable texture throws before anything changed), the description follows, and so does
// the local copy that picking casts rays into (built on the first pick, then kept in step).
#pragma once

#include <rtwall/cluster.h>
#include <rtwall/engine.h>

#include <cmath>
#include <memory>
#include <optional>
#include <vector>

namespace rtwall::wall {

class LiveScene {
public:
    LiveScene(SceneDesc desc, Master& master) : desc_(std::move(desc)), master_(master) {
        for (const InstanceDesc& in : desc_.instances) loaded_.push_back(in.visibility);
    }

    const SceneDesc& desc() const { return desc_; }
    // The viewer's camera (the scene's first): a mono wall's frames show it; each view of a
    // wall with views is derived from it (the session's frameViews).
    const CameraDesc& camera() const { return desc_.cameras.front(); }

    // An edited scene file's changes (diffScenes), as far as they may be applied: render settings
    // not while the operating point sets them (`settingsFixed`), the camera not while a path or
    // orbit moves it (`cameraScripted`), a material the master refuses not; each refusal is in
    // the result's `refused`, and what it holds is what was applied.
    SceneEdit applyEdit(const SceneDesc& edited, bool settingsFixed, bool cameraScripted) {
        SceneEdit e = diffScenes(desc_, edited);
        if (e.settings && settingsFixed) {
            e.refused.push_back("[render] changed, but --target-fps sets the render settings");
            e.settings.reset();
        }
        if (e.camera && cameraScripted) {
            e.refused.push_back("the camera changed, but a camera path or orbit moves it");
            e.camera.reset();
        }
        std::vector<std::pair<uint32_t, Material>> materials;
        for (const auto& [i, m] : e.materials) {
            try {
                setMaterial(i, m);
                materials.emplace_back(i, m);
            } catch (const InputError& err) {
                e.refused.push_back("material '" + m.name + "': " + err.what());
            }
        }
        e.materials = std::move(materials);
        for (const auto& [i, l] : e.lights) setLight(i, l);
        for (const auto& [i, p] : e.sections) setSection(i, p);
        for (const auto& [i, t] : e.transforms) setInstanceTransform(i, t);
        if (!e.visibility.empty()) setLoadedVisibility(e.visibility);
        if (e.settings) setRenderSettings(*e.settings);
        if (e.camera) setCamera(*e.camera);
        if (e.denoise) desc_.denoise = *e.denoise;  // the display side's: the session reads it per frame
        return e;
    }

    void setCamera(const CameraDesc& camera) {
        master_.setCamera(camera);
        desc_.cameras.front() = camera;
    }
    void setInstanceTransform(uint32_t instance, const Transform& transform) {
        master_.setInstanceTransform(instance, transform);
        desc_.instances[instance].transform = transform;
        if (pickScene_) {
            pickScene_->setInstanceTransform(instance, transform);
            pickScene_->commit();
        }
    }
    void setMaterial(uint32_t material, const Material& value) {
        master_.setMaterial(material, value);
        desc_.materials[material] = value;
        if (pickScene_) {  // alpha masks decide what a pick hits
            pickScene_->setMaterial(material, value);
            pickScene_->commit();
        }
    }
    void setLight(uint32_t light, const Light& value) {
        master_.setLight(light, value);
        desc_.lights[light] = value;
        if (pickScene_) {
            pickScene_->setLight(light, value);
            pickScene_->commit();
        }
    }
    void setSection(uint32_t section, const SectionPlane& plane) {
        master_.setSection(section, plane);  // throws for a bad slot or plane before anything changed
        desc_.sections[section] = plane;
        if (pickScene_) pickScene_->setSection(section, plane);  // what is cut away cannot be picked
    }
    // Hide, isolate and highlight parts by name (docs/design-review.md, "Parts"): `view` on top of what the scene
    // was loaded with (its [parts], `--hide` ...), unless `keepLoaded` is false (show all). Only
    // the instances whose visibility changes are sent. Throws InputError for a pattern that
    // matches nothing, before anything changed.
    void setPartView(const PartView& view, bool keepLoaded = true) {
        std::vector<Visibility> v = visibilityOf(desc_, view);
        if (keepLoaded)
            for (size_t i = 0; i < v.size(); ++i) v[i] = combineVisibility(loaded_[i], v[i]);
        else
            loaded_.assign(v.size(), Visibility::Shown);
        for (size_t i = 0; i < v.size(); ++i) {
            if (desc_.instances[i].visibility == v[i]) continue;
            master_.setInstanceVisibility(uint32_t(i), v[i]);
            desc_.instances[i].visibility = v[i];
            if (pickScene_) pickScene_->setInstanceVisibility(uint32_t(i), v[i]);  // a hidden part is not picked
        }
        if (pickScene_) pickScene_->commit();
        view_ = view;
    }
    const PartView& partView() const { return view_; }
    // A --watch edit of the scene file's [parts]: what the file now loads the instances with
    // (the wall's own view stays on top of it).
    void setLoadedVisibility(const std::vector<std::pair<uint32_t, Visibility>>& edits) {
        for (const auto& [i, v] : edits) loaded_.at(i) = v;
        setPartView(view_);
    }
    size_t hiddenCount() const {
        size_t n = 0;
        for (const InstanceDesc& in : desc_.instances) n += in.visibility == Visibility::Hidden;
        return n;
    }

    void setRenderSettings(const RenderSettings& settings) {
        master_.setRenderSettings(settings);
        desc_.settings = settings;
    }

    // The instance the ray through image position (x, y) of a width x height image hits first.
    std::optional<PickResult> pick(const CameraDesc& camera, int width, int height, double x, double y) {
        return pick(Camera(camera, width, height), x, y);
    }
    std::optional<PickResult> pick(const Camera& camera, double x, double y) {
        if (!pickScene_) pickScene_ = std::make_unique<Scene>(desc_);
        return rtwall::pick(*pickScene_, camera, float(x), float(y));
    }

    // The instance a ray (a tracked wand's) hits first; t in units of `direction`. The engine's
    // pick takes a camera: this is one whose single pixel's ray is this one (an off-axis window
    // of no size at origin + direction).
    std::optional<PickResult> pickRay(const Float3& origin, const Float3& direction) {
        CameraDesc c;
        c.position = origin;
        const Float3 at{origin.x + direction.x, origin.y + direction.y, origin.z + direction.z};
        c.window = ProjectionWindow{at, {0, 0, 0}, {0, 0, 0}};
        std::optional<PickResult> r = pick(c, 1, 1, 0.0, 0.0);
        if (r) {
            // The camera's ray is at - origin, the direction up to rounding.
            const Float3 d{at.x - origin.x, at.y - origin.y, at.z - origin.z};
            auto len = [](Float3 v) { return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z); };
            r->t = float(r->t * len(d) / len(direction));
        }
        return r;
    }

private:
    SceneDesc desc_;
    Master& master_;
    std::vector<Visibility> loaded_;  // per instance: as the scene was loaded (or last edited)
    PartView view_;                   // the wall's own hide/isolate/highlight on top
    std::unique_ptr<Scene> pickScene_;
};

}  // namespace rtwall::wall
