// A small assembly built in code for the hide / isolate / highlight tests (engine and cluster):
// a floor (a plain instance, no part) and an assembly "asm" of a "left" box, a "right" box and a
// "knob" sphere that belongs to the right box's node, lit from the upper left so that every part
// casts a shadow on the floor.
#pragma once

#include <rtwall/engine.h>

#include <memory>

namespace rtwall::test {

inline SceneDesc partsScene() {
    SceneDesc d;
    d.meshes.push_back({"floor", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    d.meshes.push_back({"box", "shape:box", std::make_shared<const TriangleMesh>(makeBox())});
    d.meshes.push_back({"ball", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(16, 32))});
    Material floor;
    floor.name = "floor";
    floor.color = {0.7f, 0.7f, 0.7f};
    Material paint;
    paint.name = "paint";
    paint.type = MaterialType::Phong;
    paint.color = {0.2f, 0.4f, 0.8f};
    paint.specular = {0.3f, 0.3f, 0.3f};
    d.materials = {floor, paint};
    d.parts = {{"asm", -1}, {"left", 0}, {"right", 0}, {"knob", 2}};
    InstanceDesc f;
    f.mesh = 0;
    f.transform = Transform::scale(4, 1, 4);
    InstanceDesc left{1, 1, Transform::translate(-1.3, 0.6, 0) * Transform::scale(0.6, 0.6, 0.6), 1};
    InstanceDesc right{1, 1, Transform::translate(1.3, 0.6, 0) * Transform::scale(0.6, 0.6, 0.6), 2};
    InstanceDesc knob{2, 1, Transform::translate(1.3, 1.6, 0) * Transform::scale(0.4, 0.4, 0.4), 3};
    d.instances = {f, left, right, knob};
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0.6f, -1.0f, -0.3f};
    sun.intensity = 2.0f;
    d.lights = {sun};
    CameraDesc c;
    c.position = {0, 4.5f, 6.5f};
    c.lookAt = {0, 0.4f, 0};
    d.cameras = {c};
    d.settings.width = 96;
    d.settings.height = 72;
    d.settings.tileSize = 16;
    d.settings.ambient = {0.1f, 0.1f, 0.1f};
    return d;
}

}  // namespace rtwall::test
