// Parts by name: the patterns of hide, isolate and highlight and the visibility they give.
#include <rtwall/engine.h>

namespace rtwall {

bool globMatch(const std::string& pattern, const std::string& text) {
    // Greedy with one backtrack point (the last '*'): linear in practice, never exponential.
    size_t p = 0, t = 0, star = std::string::npos, resume = 0;
    while (t < text.size()) {
        if (p < pattern.size() && pattern[p] == '*') {
            star = p++;
            resume = t;
        } else if (p < pattern.size() && pattern[p] == text[t]) {
            ++p;
            ++t;
        } else if (star != std::string::npos) {
            p = star + 1;
            t = ++resume;
        } else {
            return false;
        }
    }
    while (p < pattern.size() && pattern[p] == '*') ++p;
    return p == pattern.size();
}

std::vector<uint32_t> instancesMatching(const SceneDesc& scene, const std::string& pattern) {
    const bool byPath = pattern.find('/') != std::string::npos;
    // Parents come before their children, so one pass decides "this part or an ancestor".
    std::vector<char> matched(scene.parts.size(), 0);
    std::vector<std::string> paths(byPath ? scene.parts.size() : 0);
    for (size_t i = 0; i < scene.parts.size(); ++i) {
        const PartDesc& p = scene.parts[i];
        const bool parentKnown = p.parent >= 0 && size_t(p.parent) < i;
        if (byPath)
            paths[i] = p.parent < 0 ? p.name : parentKnown ? paths[size_t(p.parent)] + "/" + p.name : scene.partPath(int32_t(i));
        matched[i] = globMatch(pattern, byPath ? paths[i] : p.name) || (parentKnown && matched[size_t(p.parent)]);
    }
    std::vector<uint32_t> out;
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const InstanceDesc& in = scene.instances[i];
        const bool hit = in.part >= 0 && size_t(in.part) < matched.size()
                             ? matched[size_t(in.part)] != 0
                             : in.part < 0 && !byPath && in.mesh < scene.meshes.size() &&
                                   globMatch(pattern, scene.meshes[in.mesh].name);
        if (hit) out.push_back(uint32_t(i));
    }
    return out;
}

std::vector<Visibility> visibilityOf(const SceneDesc& scene, const PartView& view) {
    const size_t n = scene.instances.size();
    auto mark = [&](const std::vector<std::string>& patterns, const char* what) {
        std::vector<char> hit(n, 0);
        for (const std::string& pattern : patterns) {
            const std::vector<uint32_t> found = instancesMatching(scene, pattern);
            if (found.empty()) throw InputError(std::string(what) + " '" + pattern + "': no part or mesh matches it");
            for (uint32_t i : found) hit[i] = 1;
        }
        return hit;
    };
    const std::vector<char> isolated = mark(view.isolate, "isolate"), hidden = mark(view.hide, "hide"),
                            highlighted = mark(view.highlight, "highlight");
    std::vector<Visibility> out(n, Visibility::Shown);
    for (size_t i = 0; i < n; ++i) {
        if ((!view.isolate.empty() && !isolated[i]) || hidden[i]) out[i] = Visibility::Hidden;
        else if (highlighted[i]) out[i] = Visibility::Highlighted;
    }
    return out;
}

Visibility combineVisibility(Visibility a, Visibility b) {
    if (a == Visibility::Hidden || b == Visibility::Hidden) return Visibility::Hidden;
    return a == Visibility::Highlighted || b == Visibility::Highlighted ? Visibility::Highlighted : Visibility::Shown;
}

void applyPartView(SceneDesc& scene, const PartView& view) {
    const std::vector<Visibility> v = visibilityOf(scene, view);
    for (size_t i = 0; i < v.size(); ++i) scene.instances[i].visibility = combineVisibility(scene.instances[i].visibility, v[i]);
}

}  // namespace rtwall
