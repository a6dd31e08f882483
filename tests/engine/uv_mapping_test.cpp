// The "uv" texture mapping (issue 7): a mesh's own texture coordinates, interpolated at the hit,
// pick the texels of image and pattern textures and alpha masks (camera and shadow rays), and
// give bump mapping its tangent frame (dP/du, dP/dv). Tested against analytic pixels and the
// closed-form tangent frame.
#include "shading_scenes.h"
#include "test_util.h"

#include "material.h"
#include "shading.h"
#include "texture.h"

#include <rtwall/image.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rtwall {
namespace {

std::vector<float> renderLinear(const Scene& scene, const SceneDesc& d) {
    const RenderSettings& s = d.settings;
    std::vector<float> out(size_t(s.width) * s.height * 3);
    const Camera cam(d.cameras.front(), s.width, s.height);
    for (const TileRect& r : makeTiles(s.width, s.height, s.tileSize))
        renderTileLinear(scene, cam, r, 0, s, out.data() + (size_t(r.y0) * s.width + r.x0) * 3, size_t(s.width) * 3);
    return out;
}

// The quad [-1,1]^2 in the xz-plane, facing +y, with texture coordinates an affine function of
// the position: u = a (z + 1), v = b (1 - x) (so u runs along z and v against x: the mapping is
// neither planar xz nor any other projection).
constexpr float kA = 0.75f, kB = 0.5f;
TriangleMesh uvQuad(float a = kA, float b = kB) {
    TriangleMesh m;
    const float p[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};  // (x, z)
    std::vector<float> uv;
    for (const auto& q : p) {
        m.addVertex({q[0], 0.0f, q[1]});
        uv.push_back(a * (q[1] + 1.0f));
        uv.push_back(b * (1.0f - q[0]));
    }
    m.addTriangle(0, 2, 1);
    m.addTriangle(0, 3, 2);
    m.setUVs(uv);
    return m;
}

CameraDesc topCamera() {
    CameraDesc c;
    c.position = {0, 4, 0};
    c.lookAt = {0, 0, 0};
    c.up = {0, 0, -1};
    c.fovY = 20.0f;  // sees |x|, |z| < 0.7
    return c;
}

SceneDesc quadScene(std::shared_ptr<const TriangleMesh> mesh, const Material& m) {
    SceneDesc s;
    s.meshes.push_back({"quad", "shape:uvquad", std::move(mesh)});
    s.materials = {m};
    s.instances.push_back({0, 0, Transform{}});
    s.cameras = {topCamera()};
    test::setImage(s.settings, 48, 48, 16);
    s.settings.background = {0, 0, 0};
    s.settings.ambient = {0, 0, 0};
    return s;
}

// Where the centre of pixel (x, y) hits the plane y = 0, by the camera's own ray.
Float3 hitOnPlane(const Camera& cam, int x, int y) {
    const Float3 o = cam.origin();
    const Float3 d = cam.direction(x + 0.5f, y + 0.5f);
    return o + d * (-o.y / d.y);
}

// An 8x8 PNG of 2x2 checks (4x4 texels each), white where (column + row) is even.
std::string writeChecker(const std::filesystem::path& dir) {
    Image img;
    img.width = img.height = 8;
    img.rgb.resize(8 * 8 * 3);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const uint8_t v = ((x / 4 + y / 4) & 1) ? 0 : 255;
            uint8_t* p = img.pixel(x, y);
            p[0] = p[1] = p[2] = v;
        }
    const auto file = dir / "uv_checker.png";
    writePng(img, file);
    return file.string();
}

// An emissive quad shows its texture unlit: each pixel is the texel at the (u, v) of its hit,
// so away from check edges (1.5 texels of bilinear filtering) it is exactly black or white.
// Image row 0 is at v = 1, so the check row counts from the top: floor((1 - frac v) * 2).
TEST(UVMapping, CheckerImageOnATexturedQuadMatchesAnalyticPixels) {
    const auto dir = test::scratchDir();
    // Emissive shades emission * albedo: white emission shows the texture itself.
    Material m = test::material("screen", MaterialType::Emissive, {1, 1, 1});
    m.emission = {1, 1, 1};
    m.texture.kind = TextureKind::Image;
    m.texture.file = writeChecker(dir);
    m.texture.mapping = TextureMapping::Uv;
    const SceneDesc s = quadScene(std::make_shared<const TriangleMesh>(uvQuad()), m);
    const Scene scene(s);
    const std::vector<float> img = renderLinear(scene, s);
    const Camera cam(s.cameras.front(), s.settings.width, s.settings.height);
    int checked = 0, white = 0;
    for (int y = 0; y < s.settings.height; ++y)
        for (int x = 0; x < s.settings.width; ++x) {
            const Float3 p = hitOnPlane(cam, x, y);
            const double u = kA * (double(p.z) + 1.0), v = kB * (1.0 - double(p.x));
            const double fu = u - std::floor(u), fv = v - std::floor(v);
            const double tx = fu * 8.0, ty = (1.0 - fv) * 8.0;  // in texels
            // The texel centres of one check span [0.5, 3.5] (in texels from its edge): bilinear
            // filtering mixes only texels of that check between them.
            auto outside = [](double t) {
                const double r = std::fmod(t, 4.0);
                return r < 0.55 || r > 3.45;
            };
            if (outside(tx) || outside(ty)) continue;
            const bool isWhite = ((int(std::floor(tx / 4.0)) + int(std::floor(ty / 4.0))) & 1) == 0;
            const float* px = &img[(size_t(y) * s.settings.width + x) * 3];
            EXPECT_NEAR(px[0], isWhite ? 1.0f : 0.0f, 1e-6f) << "pixel " << x << "," << y << " uv " << u << "," << v;
            ++checked;
            white += isWhite;
        }
    EXPECT_GT(checked, 400);
    EXPECT_GT(white, checked / 5);
    EXPECT_LT(white, 4 * checked / 5);
}

// Without a mapping ("auto", the default) a mesh with texture coordinates uses them, and a mesh
// without uses planar xz as before.
TEST(UVMapping, AutoIsUvWhereTheMeshHasThemAndXzWhereNot) {
    Material m = test::material("checks", MaterialType::Emissive, {1, 1, 1});
    m.emission = {1, 1, 1};
    m.texture.kind = TextureKind::Checker;
    m.texture.color2 = {0.25f, 0.25f, 0.25f};
    m.texture.scale = 0.25f;
    auto imageWith = [&](std::shared_ptr<const TriangleMesh> mesh, TextureMapping mapping) {
        Material mm = m;
        mm.texture.mapping = mapping;
        const SceneDesc s = quadScene(std::move(mesh), mm);
        return renderLinear(Scene(s), s);
    };
    const auto withUV = std::make_shared<const TriangleMesh>(uvQuad());
    const auto plain = std::make_shared<const TriangleMesh>(makeQuad());
    EXPECT_EQ(imageWith(withUV, TextureMapping::Auto), imageWith(withUV, TextureMapping::Uv));
    EXPECT_NE(imageWith(withUV, TextureMapping::Auto), imageWith(withUV, TextureMapping::PlanarXZ));
    EXPECT_EQ(imageWith(plain, TextureMapping::Auto), imageWith(plain, TextureMapping::PlanarXZ));
}

// The tangent frame solves e1 = dPdu du1 + dPdv dv1, e2 = dPdu du2 + dPdv dv2: worked by hand
// for a triangle whose (u, v) run along z and x with scales 1/3 and 1/4.
TEST(UVMapping, TangentFrameAndSurfaceGradientAgainstHandValues) {
    TriangleMesh m;
    m.addVertex({0, 0, 0});
    m.addVertex({2, 0, 0});
    m.addVertex({0, 0, 3});
    m.addTriangle(0, 1, 2);
    m.setUVs({0.5f, 0.5f, 0.5f, 1.0f, 1.5f, 0.5f});
    Float3 dPdu, dPdv;
    ASSERT_TRUE(uvTangents(m, 0, dPdu, dPdv));
    EXPECT_EQ(dPdu.x, 0.0f);
    EXPECT_EQ(dPdu.y, 0.0f);
    EXPECT_EQ(dPdu.z, 3.0f);
    EXPECT_EQ(dPdv.x, 4.0f);
    EXPECT_EQ(dPdv.y, 0.0f);
    EXPECT_EQ(dPdv.z, 0.0f);
    // u = z / 3 + c, v = x / 4 + c': grad h = (h_v / 4, 0, h_u / 3).
    const Float3 g = uvSurfaceGradient(dPdu, dPdv, 1.5f, -2.0f);
    EXPECT_FLOAT_EQ(g.x, -0.5f);
    EXPECT_FLOAT_EQ(g.y, 0.0f);
    EXPECT_FLOAT_EQ(g.z, 0.5f);
    // Interpolation at barycentrics (0.25, 0.5): uv0 w + uv1 u + uv2 v.
    float uv[2];
    meshUVAt(m, 0, 0.25f, 0.5f, uv);
    EXPECT_FLOAT_EQ(uv[0], 0.5f * 0.25f + 0.5f * 0.25f + 1.5f * 0.5f);
    EXPECT_FLOAT_EQ(uv[1], 0.5f * 0.25f + 1.0f * 0.25f + 0.5f * 0.5f);
    // No frame where the texture coordinates have no area.
    TriangleMesh flat = m;
    flat.setUVs({0, 0, 1, 1, 2, 2});
    EXPECT_FALSE(uvTangents(flat, 0, dPdu, dPdv));
}

// Bump mapping with uv: the normal is n - grad h, h = bump * turbulence((u, 0, v) / scale) and
// grad h = h_u grad(u) + h_v grad(v) on the surface; here u = 0.75 (z + 1), v = 0.5 (1 - x), so
// grad(u) = (0, 0, 0.75), grad(v) = (-0.5, 0, 0). The material's bumped normal must be that.
TEST(UVMapping, BumpedNormalIsTheAnalyticOneFromTheTangentFrame) {
    const TriangleMesh mesh = uvQuad();
    Material desc = test::material("bumpy", MaterialType::Lambert, {1, 1, 1});
    desc.bump = 0.3f;
    desc.bumpScale = 0.2f;
    desc.bumpMapping = TextureMapping::Uv;
    const auto model = makeMaterialModel(desc);
    InstanceData inst;
    inst.mesh = &mesh;
    inst.normalMatrix[0] = inst.normalMatrix[4] = inst.normalMatrix[8] = 1.0f;
    int tested = 0;
    for (float bu : {0.1f, 0.3f, 0.45f})
        for (float bv : {0.05f, 0.2f, 0.5f}) {
            for (uint32_t prim : {0u, 1u}) {
                SurfacePoint sp;
                sp.prim = prim;
                sp.hasUV = true;
                meshUVAt(mesh, prim, bu, bv, sp.uv);
                const Float3 n = model->bumpedNormal(inst, sp, {0, 1, 0});
                Float3 G;
                turbulenceGrad(Float3{sp.uv[0], 0.0f, sp.uv[1]} * (1.0f / 0.2f), 4, G);
                const double k = 0.3 / 0.2;  // bump / scale
                const double hu = k * G.x, hv = k * G.z;
                const double gx = hv * -0.5, gz = hu * 0.75;  // h_u grad(u) + h_v grad(v)
                const double len = std::sqrt(gx * gx + 1.0 + gz * gz);
                EXPECT_NEAR(n.x, -gx / len, 2e-6) << bu << "," << bv;
                EXPECT_NEAR(n.y, 1.0 / len, 2e-6);
                EXPECT_NEAR(n.z, -gz / len, 2e-6);
                tested += std::fabs(gx) + std::fabs(gz) > 0.05;
            }
        }
    EXPECT_GT(tested, 6);  // the bump does tilt the normal
    // Seen from behind (shading normal flipped), the same bump: the bumped normal is the front
    // one flipped, not its mirror image in the surface.
    for (float bu : {0.1f, 0.3f}) {
        SurfacePoint front;
        front.prim = 0;
        front.hasUV = true;
        meshUVAt(mesh, 0, bu, 0.2f, front.uv);
        SurfacePoint back = front;
        back.frontFace = false;
        const Float3 nf = model->bumpedNormal(inst, front, {0, 1, 0});
        const Float3 nb = model->bumpedNormal(inst, back, {0, -1, 0});
        EXPECT_FLOAT_EQ(nb.x, -nf.x) << bu;
        EXPECT_FLOAT_EQ(nb.y, -nf.y);
        EXPECT_FLOAT_EQ(nb.z, -nf.z);
        EXPECT_GT(std::fabs(nf.x) + std::fabs(nf.z), 1e-3f) << "tilted";
    }
    // Object mapping on the same point uses the position instead: a different normal.
    Material objDesc = desc;
    objDesc.bumpMapping = TextureMapping::Object;
    SurfacePoint sp;
    sp.hasUV = true;
    sp.po = {0.3f, 0.0f, -0.2f};
    meshUVAt(mesh, 0, 0.3f, 0.2f, sp.uv);
    const Float3 a = makeMaterialModel(objDesc)->bumpedNormal(inst, sp, {0, 1, 0});
    const Float3 b = model->bumpedNormal(inst, sp, {0, 1, 0});
    EXPECT_NE(a.x, b.x);
}

// A lit Lambert quad with a uv bump: every pixel is (1/pi) max(0, n . l) for the analytic bumped
// normal at its hit, within the difference between Embree's hit and the exact one.
TEST(UVMapping, BumpedQuadShadesAsTheAnalyticNormalSays) {
    Material m = test::material("bumpy", MaterialType::Lambert, {1, 1, 1});
    m.bump = 0.3f;
    m.bumpScale = 0.2f;
    m.bumpMapping = TextureMapping::Uv;
    SceneDesc s = quadScene(std::make_shared<const TriangleMesh>(uvQuad()), m);
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = normalize(Float3{-0.3f, -1.0f, 0.2f});
    s.lights = {sun};
    const Scene scene(s);
    const std::vector<float> img = renderLinear(scene, s);
    const Camera cam(s.cameras.front(), s.settings.width, s.settings.height);
    const Float3 l = normalize(-sun.direction);
    double worst = 0;
    for (int y = 0; y < s.settings.height; ++y)
        for (int x = 0; x < s.settings.width; ++x) {
            const Float3 p = hitOnPlane(cam, x, y);
            const float u = kA * (p.z + 1.0f), v = kB * (1.0f - p.x);
            Float3 G;
            turbulenceGrad(Float3{u, 0.0f, v} * (1.0f / 0.2f), 4, G);
            const double k = 0.3 / 0.2, gx = k * G.z * -0.5, gz = k * G.x * 0.75;
            const double len = std::sqrt(gx * gx + 1.0 + gz * gz);
            const double cosine = (-gx * l.x + l.y - gz * l.z) / len;
            const double expected = std::max(0.0, cosine) / std::numbers::pi;
            const double got = img[(size_t(y) * s.settings.width + x) * 3];
            worst = std::max(worst, std::fabs(got - expected));
        }
    EXPECT_LT(worst, 2e-3) << "largest difference from the analytic shading";
}

// With u = x and v = z the uv bump is the object-space bump of a quad in the xz-plane: the same
// height field through the same chain rule, so the images are the same bytes.
TEST(UVMapping, UvBumpEqualsObjectBumpWhenUVsAreXz) {
    TriangleMesh mesh = makeQuad();
    std::vector<float> uv;
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        uv.push_back(mesh.position(v).x);
        uv.push_back(mesh.position(v).z);
    }
    mesh.setUVs(uv);
    auto imageWith = [&](TextureMapping bumpMapping) {
        Material m = test::material("bumpy", MaterialType::Lambert, {1, 1, 1});
        m.bump = 0.3f;
        m.bumpScale = 0.2f;
        m.bumpMapping = bumpMapping;
        SceneDesc s = quadScene(std::make_shared<const TriangleMesh>(mesh), m);
        Light sun;
        sun.type = LightType::Directional;
        sun.direction = normalize(Float3{-0.3f, -1.0f, 0.2f});
        s.lights = {sun};
        return renderLinear(Scene(s), s);
    };
    const std::vector<float> viaUV = imageWith(TextureMapping::Uv), viaObject = imageWith(TextureMapping::Object);
    EXPECT_EQ(viaUV, viaObject);
    EXPECT_EQ(imageWith(TextureMapping::Auto), viaUV);
}

// An alpha mask by uv: a checker in (u, v) cuts holes that camera rays see through and shadow
// rays pass, whatever the planar position says.
TEST(UVMapping, AlphaMaskByUvForCameraAndShadowRays) {
    // The leaf's (u, v) are its (x, z) turned a quarter: u = (z + 1) / 2, v = (1 - x) / 2.
    const auto leafMesh = std::make_shared<const TriangleMesh>(uvQuad(0.5f, 0.5f));
    SceneDesc s;
    s.meshes.push_back({"floor", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    s.meshes.push_back({"leaf", "shape:uvleaf", leafMesh});
    s.materials = test::floorAndCheckerLeaf(0.5f);
    s.materials[1].alpha.mapping = TextureMapping::Uv;
    s.instances.push_back({0, 0, Transform::scale(10, 1, 10)});
    s.instances.push_back({1, 1, Transform::translate(0, 1, 0)});
    s.lights = {test::sunFromAbove()};
    s.settings.background = {0, 0, 0};
    s.settings.ambient = {0, 0, 0};
    s.settings.width = s.settings.height = 32;
    s.settings.tileSize = 16;
    CameraDesc above = topCamera();
    above.position = {0, 5, 0};
    CameraDesc below = above;
    below.position = {0, 0.9f, 0};
    below.fovY = 60.0f;  // the floor under the leaf, |x|, |z| < 0.52
    // A hole where the check of (u, v) / 0.5 is odd (the second colour, black, below the cutoff).
    auto isHole = [](double x, double z) {
        const double u = (z + 1.0) * 0.5 / 0.5, v = (1.0 - x) * 0.5 / 0.5;
        return ((int(std::floor(u)) + int(std::floor(v))) & 1) == 1;
    };
    for (const CameraDesc& c : {above, below}) {
        SceneDesc d = s;
        d.cameras = {c};
        const Scene scene(d);
        const std::vector<float> img = renderLinear(scene, d);
        const Camera cam(c, d.settings.width, d.settings.height);
        const bool fromAbove = c.position.y > 1.0f;
        int holes = 0, solid = 0;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const Float3 o = cam.origin(), dir = cam.direction(x + 0.5f, y + 0.5f);
                // Above: the point of the leaf (y = 1) the camera sees; below: the floor point
                // (y = 0), whose shadow ray goes straight up through the leaf at the same x, z.
                const float planeY = fromAbove ? 1.0f : 0.0f;
                const Float3 p = o + dir * ((planeY - o.y) / dir.y);
                if (std::fabs(p.x) < 0.03f || std::fabs(p.z) < 0.03f) continue;  // on a check edge
                const float* px = &img[(size_t(y) * 32 + x) * 3];
                const bool hole = isHole(p.x, p.z);
                if (fromAbove) {
                    // A hole shows the lit floor (1/pi, white); the leaf is green.
                    if (hole) EXPECT_NEAR(px[0], float(1.0 / std::numbers::pi), 1e-3f) << x << "," << y;
                    else EXPECT_TRUE(px[0] < 0.01f && px[1] > 0.3f) << x << "," << y;
                } else {
                    // Under a hole the floor is lit, under the leaf it is in shadow.
                    if (hole) EXPECT_NEAR(px[0], float(1.0 / std::numbers::pi), 1e-3f) << x << "," << y;
                    else EXPECT_EQ(px[0], 0.0f) << x << "," << y;
                }
                holes += hole;
                solid += !hole;
            }
        EXPECT_GT(holes, 300);
        EXPECT_GT(solid, 300);
    }
}

}  // namespace
}  // namespace rtwall
