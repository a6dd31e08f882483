// The materials against analytic values: white furnace energy conservation for every
// material, transparent shadows through a glass slab, alpha masks for camera and shadow rays,
// ray-tree pruning, GI unbiasedness, and determinism across kernels for every material.
#include "image_compare.h"
#include "shading_scenes.h"
#include "test_util.h"

#include <rtwall/engine.h>
#include <rtwall/vec.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <set>

namespace rtwall {
namespace {

// Linear RGB of a whole frame, rendered tile by tile through renderTileLinear.
std::vector<float> renderLinear(const Scene& scene, const SceneDesc& d, uint32_t frame = 0) {
    const RenderSettings& s = d.settings;
    std::vector<float> out(size_t(s.width) * s.height * 3);
    const Camera cam(d.cameras.front(), s.width, s.height);
    for (const TileRect& r : makeTiles(s.width, s.height, s.tileSize))
        renderTileLinear(scene, cam, r, frame, s, out.data() + (size_t(r.y0) * s.width + r.x0) * 3, size_t(s.width) * 3);
    return out;
}

Image render(const Scene& scene, const SceneDesc& d, uint32_t frame = 0) {
    return renderFrame(scene, Camera(d.cameras.front(), d.settings.width, d.settings.height), d.settings, frame);
}

struct FurnaceCase {
    const char* name;
    Material material;
    bool box = false;
};

std::vector<FurnaceCase> furnaceCases() {
    std::vector<FurnaceCase> v;
    auto m = [](MaterialType t, Color c) {
        Material x;
        x.type = t;
        x.color = c;
        return x;
    };
    v.push_back({"lambert", m(MaterialType::Lambert, {1, 1, 1})});
    Material phong = m(MaterialType::Phong, {0.6f, 0.6f, 0.6f});
    phong.specular = {0.4f, 0.4f, 0.4f};
    phong.shininess = 20.0f;
    v.push_back({"phong", phong});
    v.push_back({"mirror", m(MaterialType::Mirror, {1, 1, 1})});
    Material metal = m(MaterialType::Metal, {1, 1, 1});
    metal.roughness = 0.4f;
    v.push_back({"metal", metal});
    v.push_back({"glass", m(MaterialType::Glass, {1, 1, 1})});
    Material checker = m(MaterialType::Lambert, {1, 1, 1});
    checker.texture.kind = TextureKind::Checker;
    checker.texture.color2 = {1, 1, 1};
    checker.texture.scale = 0.3f;
    v.push_back({"checker", checker});
    Material marble = checker;
    marble.texture.kind = TextureKind::Marble;
    v.push_back({"marble", marble});
    Material bumped = m(MaterialType::Lambert, {1, 1, 1});
    bumped.bump = 0.5f;
    bumped.bumpScale = 0.2f;
    v.push_back({"bump", bumped});
    Material masked = m(MaterialType::Lambert, {1, 1, 1});
    masked.alpha.kind = TextureKind::Checker;
    masked.alpha.color2 = {0, 0, 0};
    masked.alpha.scale = 0.25f;
    v.push_back({"alpha_mask", masked});
    return v;
}

// pbrt's furnace tolerance: 1.0 within 2.5% (here per colour channel, over the object's pixels).
TEST(WhiteFurnace, EveryMaterialConservesEnergy) {
    const auto dir = test::scratchDir();
    std::vector<FurnaceCase> cases = furnaceCases();
    Material volume;
    volume.type = MaterialType::Volume;
    volume.volumeFile = test::writeTestVolume(dir);
    volume.transfer = {{0.0f, {1, 1, 1}, 0.0f}, {1.0f, {1, 1, 1}, 30.0f}};
    volume.volumeStep = 0.25f;
    cases.push_back({"volume", volume, true});
    for (const FurnaceCase& c : cases) {
        const SceneDesc d = test::furnace(c.material, c.box);
        const Scene scene(d);
        const std::vector<float> img = renderLinear(scene, d);
        // The object covers the centre of the image (radius 1 at distance 4 with a 30 degree view).
        double sum = 0, minV = 1e9, maxV = -1e9;
        int n = 0;
        for (int y = 8; y < 16; ++y)
            for (int x = 8; x < 16; ++x)
                for (int ch = 0; ch < 3; ++ch) {
                    const double v = img[(size_t(y) * 24 + x) * 3 + ch];
                    sum += v;
                    minV = std::min(minV, v);
                    maxV = std::max(maxV, v);
                    ++n;
                }
        const double mean = sum / n;
        std::printf("furnace %-10s mean %.4f (min %.4f, max %.4f)\n", c.name, mean, minV, maxV);
        EXPECT_NEAR(mean, 1.0, 0.025) << c.name << " (min " << minV << ", max " << maxV << ")";
    }
}

// A glass slab of thickness d with absorption a between a directional light and a white floor:
// the shadow keeps (1 - F)^2 exp(-a d) of the light at normal incidence (docs/shading.md).
TEST(TransparentShadows, GlassSlabAttenuatesByFresnelAndAbsorption) {
    SceneDesc s;
    test::addQuadAndBox(s);
    Material floor;
    floor.color = {1, 1, 1};
    Material glass;
    glass.type = MaterialType::Glass;
    glass.color = {1, 1, 1};
    glass.absorption = {0.5f, 1.0f, 2.0f};
    s.materials = {floor, glass};
    s.instances.push_back({0, 0, Transform::scale(10, 1, 10)});
    const double thickness = 0.4;
    s.instances.push_back({1, 1, Transform::translate(0, 1, 0) * Transform::scale(3, thickness / 2, 3)});
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = {0, -1, 0};
    sun.intensity = 1.0f;
    s.lights = {sun};
    // Under the slab, looking straight down at the floor.
    s.cameras = {test::cameraAt({0, 0.5f, 0}, {0, 0, 0}, 10.0f, {0, 0, -1})};
    s.settings.width = s.settings.height = 4;
    s.settings.background = {0, 0, 0};
    const Scene scene(s);
    const std::vector<float> img = renderLinear(scene, s);
    const double f = std::pow((1.5 - 1.0) / (1.5 + 1.0), 2.0);
    const double abs[3] = {0.5, 1.0, 2.0};
    for (int ch = 0; ch < 3; ++ch) {
        const double expected = (1.0 / std::numbers::pi) * (1 - f) * (1 - f) * std::exp(-abs[ch] * thickness);
        EXPECT_NEAR(img[(1 * 4 + 1) * 3 + ch], expected, 1e-4 * 1.0 + 2e-3 * expected) << "channel " << ch;
    }
}

// A checker alpha mask: camera rays see through the holes, and shadow rays pass them.
TEST(AlphaMask, HolesAreHolesForCameraAndShadowRays) {
    SceneDesc s;
    s.meshes.push_back({"quad", "shape:quad", std::make_shared<const TriangleMesh>(makeQuad())});
    s.materials = test::floorAndCheckerLeaf(1.0f);  // cells of 1 x 1 in object units: [-1,1]^2 has 4 cells, 2 of them holes
    s.instances.push_back({0, 0, Transform::scale(10, 1, 10)});
    s.instances.push_back({0, 1, Transform::translate(0, 1, 0)});
    s.lights = {test::sunFromAbove()};
    s.settings.background = {0, 0, 0};
    s.settings.width = s.settings.height = 32;
    // From above: half the leaf is green, half shows the lit floor (1/pi).
    CameraDesc above;
    above.position = {0, 5, 0};
    above.lookAt = {0, 0, 0};
    above.up = {0, 0, -1};
    above.fovY = 20.0f;  // covers |x|, |z| < 0.88: only the leaf
    // From below the leaf, between it and the floor: the floor shows the leaf's shadow pattern.
    CameraDesc below = above;
    below.position = {0, 0.9f, 0};
    below.fovY = 60.0f;  // covers |x|, |z| < 0.52 on the floor
    s.cameras = {above, below};
    // The pixel centres of (i, i) lie exactly on the quad's diagonal, and the shadow rays there
    // run straight down it: Embree's fast quad intersector let one of the 32 through, which is
    // why a quad BVH is always robust now. The scene stays as it is (fast traversal asked for).
    const Scene scene(s);
    int green = 0, floorLit = 0;
    std::vector<float> img = renderLinear(scene, s);
    for (size_t p = 0; p < 32 * 32; ++p) {
        green += img[3 * p] < 0.01f && img[3 * p + 1] > 0.3f;
        floorLit += std::fabs(img[3 * p] - float(1.0 / std::numbers::pi)) < 1e-3f;
    }
    EXPECT_EQ(green, 512);
    EXPECT_EQ(floorLit, 512);
    SceneDesc s2 = s;
    s2.cameras = {below};
    img = renderLinear(scene, s2);
    int lit = 0, dark = 0;
    for (size_t p = 0; p < 32 * 32; ++p) {
        lit += std::fabs(img[3 * p] - float(1.0 / std::numbers::pi)) < 1e-3f;
        dark += img[3 * p] == 0.0f;
    }
    EXPECT_EQ(lit, 512);
    EXPECT_EQ(dark, 512);
}

class Zoo : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new std::filesystem::path(std::filesystem::path(RTWALL_BINARY_DIR) / "test-scratch" / "zoo");
        std::filesystem::create_directories(*dir_);
        desc_ = new SceneDesc(test::materialZoo(*dir_, 64, 48));
        scene_ = new Scene(*desc_);
    }
    static void TearDownTestSuite() {
        delete scene_;
        delete desc_;
        delete dir_;
    }
    static std::filesystem::path* dir_;
    static SceneDesc* desc_;
    static Scene* scene_;
};
std::filesystem::path* Zoo::dir_ = nullptr;
SceneDesc* Zoo::desc_ = nullptr;
Scene* Zoo::scene_ = nullptr;

// The zoo's pictures, for people to look at (test-scratch/zoo/zoo.png and zoo_gi.png): each file
// holds what was rendered, shows the scene (many colours, not just the background), and path
// tracing adds light: the background's sky and the bounces between objects, which the Whitted
// image lacks (the zoo has no ambient term), so the GI image is brighter on average.
TEST_F(Zoo, WritesItsImages) {
    double meanLinear[2] = {0, 0};
    for (bool gi : {false, true}) {
        SceneDesc d = *desc_;
        d.settings.width = 320;
        d.settings.height = 240;
        d.settings.gi = gi;
        d.settings.samples = gi ? 16 : 4;
        const Image img = render(*scene_, d);
        const auto file = *dir_ / (gi ? "zoo_gi.png" : "zoo.png");
        std::filesystem::remove(file);
        writePng(img, file);
        const Image back = readPng(file);
        EXPECT_EQ(back.width, 320);
        EXPECT_EQ(back.height, 240);
        EXPECT_EQ(back.rgb, img.rgb) << file;
        std::set<uint32_t> colours;
        size_t background = 0;
        const float bgLinear[3] = {d.settings.background.x, d.settings.background.y, d.settings.background.z};
        uint8_t bg[3];
        linearToSrgb8(bgLinear, 3, bg);
        double sum = 0;
        for (size_t i = 0; i + 2 < img.rgb.size(); i += 3) {
            colours.insert(uint32_t(img.rgb[i]) << 16 | uint32_t(img.rgb[i + 1]) << 8 | img.rgb[i + 2]);
            background += img.rgb[i] == bg[0] && img.rgb[i + 1] == bg[1] && img.rgb[i + 2] == bg[2];
            for (int c = 0; c < 3; ++c) {
                const double v = img.rgb[i + size_t(c)] / 255.0;
                sum += v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
            }
        }
        meanLinear[gi] = sum / double(img.rgb.size());
        EXPECT_GT(colours.size(), 2000u) << file;
        EXPECT_LT(background, img.rgb.size() / 3 / 2) << file << ": mostly background";
    }
    std::printf("mean linear value: Whitted %.4f, GI %.4f\n", meanLinear[0], meanLinear[1]);
    EXPECT_GT(meanLinear[1], meanLinear[0] * 1.1) << "path tracing should add the sky's and the bounces' light";
}

TEST_F(Zoo, PacketAndSingleKernelsBitIdenticalForEveryMaterialAndGi) {
    for (bool gi : {false, true}) {
        SceneDesc d = *desc_;
        d.settings.gi = gi;
        d.settings.samples = gi ? 2 : 1;
        SceneDesc single = d;
        single.settings.kernel = KernelType::Single;
        const Image a = render(*scene_, d, 3), b = render(*scene_, single, 3);
        EXPECT_EQ(test::differingBytes(a, b), 0u) << "gi " << gi;
        // Tile size and thread count do not matter either.
        SceneDesc other = d;
        other.settings.tileSize = 7;
        other.settings.threads = 3;
        EXPECT_EQ(test::differingBytes(a, render(*scene_, other, 3)), 0u) << "gi " << gi;
    }
}

// The zoo's area light shines on the scene (it once pointed away, so every test that relied on
// it ran without it): with it the floor under it is brighter than with the point light alone,
// by at least a third of what the light's irradiance there predicts, and without shadows the
// light's contribution is larger still (the sphere shadows part of the floor under it).
TEST_F(Zoo, AreaLightLightsTheScene) {
    SceneDesc with = *desc_;
    SceneDesc without = *desc_;
    ASSERT_EQ(without.lights.size(), 2u);
    ASSERT_EQ(without.lights[1].type, LightType::Area);
    without.lights.resize(1);
    with.settings.samples = without.settings.samples = 16;
    const Scene sw(with), so(without);
    const std::vector<float> a = renderLinear(sw, with), b = renderLinear(so, without);
    double gained = 0;
    size_t brighter = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        gained += double(a[i]) - b[i];
        brighter += a[i] > b[i] + 1e-3f;
    }
    std::printf("area light: %zu of %zu values brighter, mean gain %.4f\n", brighter, a.size(), gained / double(a.size()));
    // Irradiance of a 1 x 1 light of intensity 3 from 4.5 above the floor: about 3 / 4.5^2 = 0.15,
    // times the floor's albedo / pi (checker 0.8 / 0.4: 0.1 to 0.2 linear) where it is not shadowed.
    EXPECT_GT(brighter, a.size() / 10);
    EXPECT_GT(gained / double(a.size()), 0.002);
}

TEST_F(Zoo, PruningAtZeroIsExactlyUnprunedAndDefaultIsClose) {
    SceneDesc off = *desc_;
    off.settings.pruneThreshold = -1.0f;  // no ray can fall below: pruning switched off
    SceneDesc zero = *desc_;
    zero.settings.pruneThreshold = 0.0f;
    SceneDesc def = *desc_;
    def.settings.pruneThreshold = 0.002f;
    TileStats so, sz, sd;
    const Camera cam(desc_->cameras.front(), desc_->settings.width, desc_->settings.height);
    const Image a = renderFrame(*scene_, cam, off.settings, 0, &so);
    const Image b = renderFrame(*scene_, cam, zero.settings, 0, &sz);
    const Image c = renderFrame(*scene_, cam, def.settings, 0, &sd);
    EXPECT_EQ(test::differingBytes(a, b), 0u);
    EXPECT_EQ(so.rays, sz.rays);
    EXPECT_LT(sd.rays, so.rays);
    // Stated error at the default 0.002: no channel more than 2 levels off, mean below 0.05 levels.
    int maxDiff = 0;
    double sum = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        const int dlt = std::abs(int(a.rgb[i]) - int(c.rgb[i]));
        maxDiff = std::max(maxDiff, dlt);
        sum += dlt;
    }
    EXPECT_LE(maxDiff, 2);
    EXPECT_LT(sum / double(a.rgb.size()), 0.05);
}

// Deep glass in front of a bright emitter (the headlight's situation: many interfaces, each
// splitting a path, and radiance 30 behind them), 16x12 pixels.
SceneDesc deepGlass() {
    SceneDesc s;
    test::addQuadAndBox(s);
    s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(12, 24))});
    Material lamp = test::material("lamp", MaterialType::Emissive, {1, 1, 1});
    lamp.emission = {30, 28, 24};
    Material glass = test::material("glass", MaterialType::Glass, {0.98f, 0.98f, 1.0f});
    glass.ior = 1.5f;
    Material mirror = test::material("mirror", MaterialType::Mirror, {0.9f, 0.9f, 0.9f});
    s.materials = {lamp, glass, mirror};
    // The lamp behind, a mirror floor, three glass slabs and a glass ball between.
    s.instances.push_back({0, 0, Transform::translate(0, 0, -3) * Transform::rotateDegrees(1, 0, 0, 90) *
                                     Transform::scale(0.6, 1, 0.6)});
    s.instances.push_back({0, 2, Transform::translate(0, -1.2, 0) * Transform::scale(6, 1, 6)});
    for (int i = 0; i < 3; ++i)
        s.instances.push_back({1, 1, Transform::translate(0, 0, -1.6 + 0.7 * i) * Transform::scale(1.4, 1.4, 0.08)});
    s.instances.push_back({2, 1, Transform::translate(0.3, 0.1, 0.6) * Transform::scale(0.4, 0.4, 0.4)});
    s.cameras = {test::cameraAt({0.4f, 0.5f, 4.0f}, {0, 0, -2}, 35.0f)};
    test::setImage(s.settings, 16, 12, 16);
    s.settings.maxDepth = 12;
    s.settings.background = {0.02f, 0.02f, 0.03f};
    s.settings.ambient = {0, 0, 0};
    s.settings.shadows = false;
    return s;
}

// Deep glass. At the default threshold the roulette keeps
// the image unbiased: the mean of many independent roulettes (here 256 samples per pixel, each
// with its own coin) matches the unpruned image. Stated error: the whole image's energy within
// 0.5%, every pixel within 3% + 0.002 linear. Dropping the sub-threshold rays instead (the
// rule before the roulette) loses 1.4% of the energy and misses the pixel bound 25-fold; the
// roulette traces 40.6 rays per sample here (39 before the dominant child went on without a coin), dropping 20, unpruned 332.
TEST(Pruning, RouletteAtTheDefaultIsUnbiasedThroughDeepGlass) {
    const SceneDesc s = deepGlass();
    const Scene scene(s);

    SceneDesc ref = s;
    ref.settings.pruneThreshold = 0.0f;
    SceneDesc def = s;
    def.settings.pruneThreshold = 0.002f;
    def.settings.samples = 256;  // without GI only the roulette differs between samples
    const Camera camera(s.cameras.front(), s.settings.width, s.settings.height);
    TileStats rs, ds;
    const std::vector<float> a = renderLinear(scene, ref), b = renderLinear(scene, def);
    renderFrame(scene, camera, ref.settings, 0, &rs);
    renderFrame(scene, camera, def.settings, 0, &ds);
    double ea = 0, eb = 0, worst = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        ea += a[i];
        eb += b[i];
        worst = std::max(worst, std::fabs(double(a[i]) - b[i]) / (0.03 * a[i] + 0.002));
        EXPECT_NEAR(b[i], a[i], 0.03 * a[i] + 0.002) << "pixel " << i / 3 << " channel " << i % 3;
    }
    std::printf("deep glass: energy unpruned %.4f, roulette at 0.002 %.4f (%.3f%%), worst pixel %.2f of its bound; "
                "rays per pixel sample %.1f unpruned, %.1f pruned\n",
                ea, eb, 100.0 * (eb - ea) / ea, worst, double(rs.rays) / (16 * 12),
                double(ds.rays) / (16 * 12 * 256));
    EXPECT_NEAR(eb / ea, 1.0, 0.005);
    // The scene is deep enough that the threshold matters at all.
    EXPECT_LT(double(ds.rays) / 256, 0.5 * double(rs.rays));
}

// Where frames differ without path tracing (here an area light: a random point on it per
// shading point), rtwall run averages the frames of a still view, and that average must
// converge to the box-filtered, unpruned image: each frame takes its own sub-pixel positions
// and its own pruning coins. Checked per pixel and channel by a z-test of the mean of 256
// one-sample frames at the default threshold against a 16x16-supersampled unpruned render,
// with the spread measured from the frames themselves (the reference's own spread is at most
// the same again: as many samples, stratified). Stated error: no more than 1% of the values
// beyond 4.5 standard deviations, and the image's energy (the sum of all values) within 4.5 of
// its standard deviations. Before, every frame sampled the pixel centres with frame 0's coins:
// the lamp's and the slabs' edge pixels and the pruned paths never converged (144 of the 576
// values beyond, the energy 13% low). (The glass ball
// of the deep-glass scene is left out, and the floor is not a rough metal: each focuses the
// lamp, radiance 30, into a few of 256 samples, which all 256 frames miss often enough to make
// the per-pixel spread an underestimate.)
TEST(Pruning, FramesOfARandomSceneAverageToTheSupersampledUnprunedImage) {
    SceneDesc s = deepGlass();
    s.materials[2] = test::material("floor", MaterialType::Lambert, {0.5f, 0.5f, 0.5f});
    Light area;
    area.type = LightType::Area;
    area.position = {-1.0f, 3.0f, -1.0f};
    area.edge1 = {2, 0, 0};
    area.edge2 = {0, 0, 2};  // cross points down
    area.intensity = 2.0f;
    s.lights = {area};
    s.instances.pop_back();
    ASSERT_TRUE(rendersStochastically(s));
    const Scene scene(s);

    SceneDesc ref = s;
    ref.settings.pruneThreshold = 0.0f;
    ref.settings.supersample = 16;
    const std::vector<float> truth = renderLinear(scene, ref);
    SceneDesc one = s;
    one.settings.pruneThreshold = 0.002f;
    const int frames = 256;
    std::vector<double> sum(truth.size(), 0.0), sq(truth.size(), 0.0);
    double eSum = 0, eSq = 0;  // the image's energy per frame
    for (int f = 1; f <= frames; ++f) {
        const std::vector<float> img = renderLinear(scene, one, uint32_t(f));
        double e = 0;
        for (size_t i = 0; i < img.size(); ++i) {
            sum[i] += img[i];
            sq[i] += double(img[i]) * img[i];
            e += img[i];
        }
        eSum += e;
        eSq += e * e;
    }
    // The standard deviation of the difference of two means of `frames` samples each, from the
    // frames' sample variance (plus a floor for values that never vary, such as the background).
    auto sdOfDifference = [&](double s1, double s2) {
        const double mean = s1 / frames;
        const double var = std::max(0.0, s2 / frames - mean * mean) * frames / (frames - 1);
        return std::sqrt(2.0 * var / frames);
    };
    int beyond = 0;
    double et = 0;
    for (size_t i = 0; i < truth.size(); ++i) {
        if (std::fabs(sum[i] / frames - truth[i]) > 4.5 * (sdOfDifference(sum[i], sq[i]) + 1e-4)) ++beyond;
        et += truth[i];
    }
    const double em = eSum / frames, esd = sdOfDifference(eSum, eSq);
    std::printf("area light, deep glass: %d of %zu values beyond 4.5 sd; energy %.2f against %.2f (sd %.2f)\n", beyond,
                truth.size(), em, et, esd);
    EXPECT_LE(beyond, int(truth.size() / 100));
    EXPECT_LT(std::fabs(em - et), 4.5 * esd);
}

// Whether frames take their own sub-pixel positions and coins follows the scene as it is
// changed: a light or material change that makes it random (or not) renders as a scene built
// that way from the start does.
TEST(Pruning, ChangedSceneSamplesAsOneBuiltThatWay) {
    SceneDesc s = deepGlass();
    s.materials[2] = test::material("floor", MaterialType::Lambert, {0.5f, 0.5f, 0.5f});
    Light point;
    point.position = {0, 3, 0};
    s.lights = {point};
    ASSERT_FALSE(rendersStochastically(s));
    Scene scene(s);
    Light area = point;
    area.type = LightType::Area;
    SceneDesc withArea = s;
    withArea.lights = {area};
    Material rough = test::material("rough", MaterialType::Metal, {0.9f, 0.9f, 0.9f});
    rough.roughness = 0.2f;
    SceneDesc withRough = s;
    withRough.materials[2] = rough;
    scene.setLight(0, area);
    EXPECT_EQ(renderLinear(scene, withArea, 3), renderLinear(Scene(withArea), withArea, 3)) << "area light";
    scene.setLight(0, point);
    EXPECT_EQ(renderLinear(scene, s, 3), renderLinear(Scene(s), s, 3)) << "back to the point light";
    scene.setMaterial(2, rough);
    scene.commit();
    EXPECT_EQ(renderLinear(scene, withRough, 3), renderLinear(Scene(withRough), withRough, 3)) << "rough metal";
}

// Spherical and cylindrical texture mappings on a unit sphere, against the checker each pixel
// must show by spherical trigonometry: the camera ray is intersected with the ideal sphere, and
// its longitude (degrees from +z towards +x) and latitude (degrees from the -y pole) or height
// pick the check. An emissive material shows the texture unlit, so the linear pixel is exactly
// one of the two colours. Pixels within 2 degrees (0.01 in height) of a check edge or near the
// silhouette are skipped: the tessellated sphere moves hits by less than that.
TEST(TextureMappings, SphericalAndCylindricalCheckersMatchAnalyticPixels) {
    for (TextureMapping mapping : {TextureMapping::Spherical, TextureMapping::Cylindrical}) {
        SceneDesc s;
        s.meshes.push_back({"sphere", "shape:sphere", std::make_shared<const TriangleMesh>(makeSphere(64, 128))});
        Material m = test::material("globe", MaterialType::Emissive, {0.8f, 0.8f, 0.8f});
        m.emission = {1, 1, 1};
        m.texture.kind = TextureKind::Checker;
        m.texture.color2 = {0.2f, 0.2f, 0.2f};
        m.texture.scale = 0.125f;  // 8 checks around, 8 from pole to pole (or 1/8 unit high)
        m.texture.mapping = mapping;
        s.materials = {m};
        s.instances.push_back({0, 0, Transform{}});
        // Sees the +y pole and the +x/+z quadrant.
        s.cameras = {test::cameraAt({1.5f, 1.8f, 3.0f}, {0, 0, 0}, 45.0f)};
        test::setImage(s.settings, 48, 40, 16);
        s.settings.background = {0, 0, 0};
        s.settings.ambient = {0, 0, 0};
        const Scene scene(s);
        const std::vector<float> img = renderLinear(scene, s);
        const Camera camera(s.cameras.front(), s.settings.width, s.settings.height);
        const Float3 o = camera.origin();
        int checked = 0, light = 0;
        for (int y = 0; y < s.settings.height; ++y)
            for (int x = 0; x < s.settings.width; ++x) {
                const Float3 d = normalize(camera.direction(x + 0.5f, y + 0.5f));
                const float b = dot(o, d), c = dot(o, o) - 1.0f, disc = b * b - c;
                if (disc < 0.05f) continue;  // a miss, or too near the silhouette
                const Float3 p = o + d * (-b - std::sqrt(disc));
                const double deg = 180.0 / std::numbers::pi;
                double lon = std::atan2(double(p.x), double(p.z)) * deg;
                if (lon < 0) lon += 360.0;
                const double column = lon / 45.0;
                double row;
                if (mapping == TextureMapping::Spherical) row = (90.0 + std::asin(double(p.y)) * deg) / 22.5;
                else row = double(p.y) / 0.125;
                const double rowMargin = mapping == TextureMapping::Spherical ? 2.0 / 22.5 : 0.01 / 0.125;
                if (std::fabs(column - std::round(column)) < 2.0 / 45.0 || std::fabs(row - std::round(row)) < rowMargin)
                    continue;
                const bool odd = (int(std::floor(column)) + int(std::floor(row))) & 1;
                const float expected = odd ? 0.2f : 0.8f;
                const float* px = &img[(size_t(y) * s.settings.width + x) * 3];
                EXPECT_EQ(px[0], expected) << (mapping == TextureMapping::Spherical ? "spherical" : "cylindrical")
                                           << " pixel " << x << "," << y << " lon " << lon << " row " << row;
                ++checked;
                light += !odd;
            }
        EXPECT_GT(checked, 300);
        EXPECT_GT(light, checked / 4);
        EXPECT_LT(light, 3 * checked / 4);
    }
}

TEST_F(Zoo, FalseColourViewsRender) {
    for (ViewMode v : {ViewMode::Depth, ViewMode::Rays, ViewMode::TileTime, ViewMode::Client}) {
        SceneDesc d = *desc_;
        d.settings.view = v;
        const Image img = render(*scene_, d);
        std::set<uint32_t> colours;
        for (size_t i = 0; i + 2 < img.rgb.size(); i += 3)
            colours.insert(uint32_t(img.rgb[i]) << 16 | uint32_t(img.rgb[i + 1]) << 8 | img.rgb[i + 2]);
        if (v == ViewMode::Client) EXPECT_EQ(colours.size(), 1u);  // one machine: one client
        else EXPECT_GT(colours.size(), 1u);
    }
}

// GI is unbiased: the mean of many independent low-sample frames matches a high-sample
// reference per pixel. Per-pixel z-test (Welch's statistic with the reference's own variance)
// at alpha = 0.01 with Sidak correction over every pixel and channel.
TEST(GlobalIllumination, EstimatorIsUnbiased) {
    SceneDesc s;
    test::addQuadAndBox(s);
    Material white;
    white.color = {0.8f, 0.8f, 0.8f};
    Material red;
    red.color = {0.8f, 0.2f, 0.2f};
    s.materials = {white, red};
    s.instances.push_back({0, 0, Transform::scale(4, 1, 4)});
    s.instances.push_back({1, 1, Transform::translate(0, 0.5, 0) * Transform::scale(0.5, 0.5, 0.5)});
    Light area;
    area.type = LightType::Area;
    area.position = {-0.5f, 2.5f, -0.5f};
    area.edge1 = {1, 0, 0};
    area.edge2 = {0, 0, 1};  // cross(edge1, edge2) = (0,-1,0): it shines down (it pointed up before)
    area.intensity = 4.0f;
    s.lights = {area};
    s.cameras = {test::cameraAt({2, 2, 3}, {0, 0.3f, 0})};
    test::setImage(s.settings, 8, 6, 8);
    s.settings.gi = true;
    s.settings.maxDepth = 6;
    s.settings.pruneThreshold = 0.0f;
    s.settings.background = {0.1f, 0.1f, 0.1f};
    const Scene scene(s);
    auto stats = [&](int frames, uint32_t firstFrame, int spp, std::vector<double>& mean, std::vector<double>& var) {
        SceneDesc d = s;
        d.settings.samples = spp;
        const size_t n = size_t(d.settings.width) * d.settings.height * 3;
        std::vector<double> sum(n, 0.0), sum2(n, 0.0);
        for (int f = 0; f < frames; ++f) {
            const std::vector<float> img = renderLinear(scene, d, firstFrame + uint32_t(f));
            for (size_t i = 0; i < n; ++i) {
                sum[i] += img[i];
                sum2[i] += double(img[i]) * img[i];
            }
        }
        mean.resize(n);
        var.resize(n);
        for (size_t i = 0; i < n; ++i) {
            mean[i] = sum[i] / frames;
            var[i] = std::max(0.0, (sum2[i] / frames - mean[i] * mean[i]) * frames / (frames - 1)) / frames;  // of the mean
        }
    };
    std::vector<double> m, v, rm, rv;
    stats(200, 0, 2, m, v);        // the estimator under test: 200 frames of 2 samples
    stats(100, 100000, 32, rm, rv);  // reference: independent seeds, 3200 samples per pixel
    const size_t n = m.size();
    const double threshold = test::sidakThreshold(0.01, n);
    int failures = 0;
    for (size_t i = 0; i < n; ++i) {
        const double se = std::sqrt(v[i] + rv[i]);
        if (se == 0.0) {
            EXPECT_NEAR(m[i], rm[i], 1e-6);  // no variance: a background pixel
            continue;
        }
        const double z = std::fabs(m[i] - rm[i]) / se;
        if (z > threshold) ++failures;
    }
    EXPECT_EQ(failures, 0) << "z threshold " << threshold;
    std::printf("GI z-test: %zu values, threshold |z| > %.2f, %d failures\n", n, threshold, failures);
}

TEST(Accumulator, MeanOfFramesInLinearLight) {
    Image a, b;
    a.width = b.width = 1;
    a.height = b.height = 1;
    a.rgb = {0, 255, 128};
    b.rgb = {255, 255, 128};
    Accumulator acc;
    acc.add(a);
    acc.add(b);
    const Image r = acc.resolve();
    EXPECT_EQ(acc.frames(), 2);
    const float half = 0.5f;
    uint8_t halfSrgb;
    linearToSrgb8(&half, 1, &halfSrgb);
    EXPECT_EQ(r.rgb[0], halfSrgb);
    EXPECT_EQ(r.rgb[1], 255);
    EXPECT_EQ(r.rgb[2], 128);
    acc.reset();
    acc.add(a);
    EXPECT_EQ(acc.resolve().rgb, a.rgb);
}

}  // namespace
}  // namespace rtwall

namespace rtwall {
namespace {

// Scene-file mistakes in the shading keys: one line naming the file, the line and the key.
TEST(ShadingSceneFile, BadInputNamesFileLineAndKey) {
    const auto dir = test::scratchDir();
    test::writeFile(dir / "garbage.png", "not an image at all");
    test::writeFile(dir / "garbage.vti", "<VTKFile nonsense");
    const std::string head = "[[mesh]]\nname = \"b\"\nshape = \"box\"\n";
    struct Case {
        std::string body, expect;
    };
    const std::vector<Case> cases = {
        {"[[material]]\nname = \"m\"\ntexture = \"image\"\ntexture_file = \"missing.png\"\n", ":7: [[material]] #1: key 'texture_file'"},
        {"[[material]]\nname = \"m\"\ntexture = \"image\"\ntexture_file = \"garbage.png\"\n", "texture must be a PNG or a JPEG"},
        {"[[material]]\nname = \"m\"\ntexture = \"plaid\"\n", "key 'texture'"},
        {"[[material]]\nname = \"m\"\ntype = \"volume\"\nvolume_file = \"garbage.vti\"\n", "key 'volume_file'"},
        {"[[material]]\nname = \"m\"\ntype = \"volume\"\n", "missing required key 'volume_file'"},
        {"[[material]]\nname = \"m\"\ntype = \"metal\"\nroughness = 2\n", "key 'roughness'"},
        {"[[material]]\nname = \"m\"\ntype = \"glass\"\nabsorption = [-1, 0, 0]\n", "key 'absorption'"},
        {"[render]\nview = \"xray\"\n", "key 'view'"},
        {"[render]\nprune_threshold = -0.1\n", "key 'prune_threshold'"},
        {"[[light]]\ntype = \"area\"\nposition = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [2, 0, 0]\n", "no area"},
        {"[[light]]\nposition = [0, 0, 0]\ntwo_sided = true\n", ":6: [[light]] #1: key 'two_sided': only area lights have sides"},
        {"[[light]]\ntype = \"area\"\nposition = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [0, 0, 1]\ntwo_sided = 1\n",
         "key 'two_sided'"},
        {"[[material]]\nname = \"m\"\ntype = \"emissive\"\ntwo_sided = \"yes\"\n", ":7: [[material]] #1: key 'two_sided'"},
    };
    for (const Case& c : cases) {
        const auto file = test::writeFile(dir / "s.toml", head + c.body);
        const std::string msg = test::inputErrorOf([&] { loadSceneFile(file); });
        EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
        EXPECT_NE(msg.find("s.toml:"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    // A volume file that is not there, handed straight to the engine: an InputError, not a crash.
    Material m;
    m.type = MaterialType::Volume;
    m.volumeFile = (dir / "nope.vti").string();
    SceneDesc d = test::furnace(m, true);
    EXPECT_NE(test::inputErrorOf([&] { Scene s(d); }).find("nope.vti"), std::string::npos);
}

// [denoise] (issue 28): every key read back; each bad value one line naming the file, the line
// and the key (a NaN, a negative or zero level, an unknown mode, a key that does not exist).
TEST(ShadingSceneFile, DenoiseTable) {
    const auto dir = test::scratchDir();
    const std::string head = "[[mesh]]\nname = \"b\"\nshape = \"box\"\n";
    const auto good = test::writeFile(dir / "d.toml", head + "[denoise]\nmode = \"svgf\"\nlevels = 3\nhistory = 8\n"
                                                             "sigma_depth = 2\nsigma_normal = 64\nsigma_luminance = 8\n");
    const SceneDesc d = loadSceneFile(good);
    EXPECT_EQ(d.denoise.mode, DenoiseSettings::Mode::Svgf);
    EXPECT_EQ(d.denoise.levels, 3);
    EXPECT_EQ(d.denoise.history, 8);
    EXPECT_EQ(d.denoise.sigmaDepth, 2.0f);
    EXPECT_EQ(d.denoise.sigmaNormal, 64.0f);
    EXPECT_EQ(d.denoise.sigmaLuminance, 8.0f);
    EXPECT_EQ(loadSceneFile(test::writeFile(dir / "n.toml", head)).denoise, DenoiseSettings{}) << "off unless asked for";
    struct Case {
        std::string body, expect;
    };
    const std::vector<Case> cases = {
        {"[denoise]\nmode = \"magic\"\n", ":5: [denoise]: key 'mode'"},
        {"[denoise]\nlevels = -1\n", ":5: [denoise]: key 'levels'"},
        {"[denoise]\nlevels = 0\n", "key 'levels'"},
        {"[denoise]\nlevels = 11\n", "key 'levels'"},
        {"[denoise]\nhistory = 0\n", "key 'history'"},
        {"[denoise]\nsigma_luminance = nan\n", ":5: [denoise]: key 'sigma_luminance'"},
        {"[denoise]\nsigma_depth = -1\n", "key 'sigma_depth'"},
        {"[denoise]\nsigma_normal = inf\n", "key 'sigma_normal'"},
        {"[denoise]\nsigma_luminance = \"four\"\n", "key 'sigma_luminance'"},
        {"[denoise]\nstrength = 3\n", "strength"},
        {"denoise = \"svgf\"\n", "key 'denoise'"},
    };
    for (const Case& c : cases) {
        const auto file = test::writeFile(dir / "s.toml", head + c.body);
        const std::string msg = test::inputErrorOf([&] { loadSceneFile(file); });
        EXPECT_NE(msg.find(c.expect), std::string::npos) << c.body << ": " << msg;
        EXPECT_NE(msg.find("s.toml:"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    EXPECT_EQ(test::inputErrorOf([] { denoiseModeFromName("fast"); }), "unknown denoise mode 'fast' (off, temporal, svgf)");
}

// Every key of the format, read back.
TEST(ShadingSceneFile, ReadsEveryShadingKey) {
    const auto dir = test::scratchDir();
    const std::string tex = test::writeTestTexture(dir), vol = test::writeTestVolume(dir);
    const auto file = test::writeFile(dir / "s.toml", R"(
[render]
prune_threshold = 0.01
gi = true
samples = 3
view = "depth"
[[mesh]]
name = "b"
shape = "box"
[[material]]
name = "m"
type = "metal"
roughness = 0.3
texture = "image"
texture_file = "texture.png"
texture_scale = 2
texture_mapping = "xy"
bump = 0.5
bump_scale = 0.2
alpha = "checker"
alpha_color2 = [0, 0, 0]
alpha_cutoff = 0.25
alpha_channel = "alpha"
alpha_mode = "hashed"
opacity = 0.75
emission = [0.5, 0, 0]
two_sided = true
[[material]]
name = "v"
type = "volume"
volume_file = "blob.vti"
volume_step = 0.3
transfer = [[0, 1, 1, 1, 0], [1, 1, 0.5, 0, 4]]
[[material]]
name = "g"
type = "glass"
absorption = [0.1, 0.2, 0.3]
[[light]]
type = "area"
position = [0, 2, 0]
edge1 = [1, 0, 0]
edge2 = [0, 0, -1]
intensity = 3
two_sided = true
[[light]]
type = "area"
position = [0, 2, 0]
edge1 = [1, 0, 0]
edge2 = [0, 0, 1]
)");
    const SceneDesc s = loadSceneFile(file);
    EXPECT_FLOAT_EQ(s.settings.pruneThreshold, 0.01f);
    EXPECT_TRUE(s.settings.gi);
    EXPECT_EQ(s.settings.samples, 3);
    EXPECT_EQ(s.settings.view, ViewMode::Depth);
    const Material& m = s.materials[0];
    EXPECT_EQ(m.type, MaterialType::Metal);
    EXPECT_FLOAT_EQ(m.roughness, 0.3f);
    EXPECT_EQ(m.texture.kind, TextureKind::Image);
    EXPECT_EQ(m.texture.mapping, TextureMapping::PlanarXY);
    EXPECT_FLOAT_EQ(m.bump, 0.5f);
    EXPECT_EQ(m.alpha.kind, TextureKind::Checker);
    EXPECT_FLOAT_EQ(m.alphaCutoff, 0.25f);
    EXPECT_EQ(m.alphaChannel, AlphaChannel::Alpha);
    EXPECT_EQ(m.alphaMode, AlphaMode::Hashed);
    EXPECT_FLOAT_EQ(m.opacity, 0.75f);
    EXPECT_EQ(s.materials[1].alphaMode, AlphaMode::Mask);  // the defaults
    EXPECT_EQ(s.materials[1].alphaChannel, AlphaChannel::Red);
    EXPECT_FLOAT_EQ(s.materials[1].opacity, 1.0f);
    EXPECT_FLOAT_EQ(m.emission.x, 0.5f);
    EXPECT_EQ(s.materials[1].transfer.size(), 2u);
    EXPECT_FLOAT_EQ(s.materials[1].volumeStep, 0.3f);
    EXPECT_FLOAT_EQ(s.materials[2].absorption.z, 0.3f);
    EXPECT_EQ(s.lights[0].type, LightType::Area);
    EXPECT_TRUE(m.twoSided);
    EXPECT_FALSE(s.materials[2].twoSided);  // one-sided unless asked (docs/shading.md)
    EXPECT_TRUE(s.lights[0].twoSided);
    EXPECT_FALSE(s.lights[1].twoSided);
    const Scene scene(s);  // textures and volume load
}

}  // namespace
}  // namespace rtwall
