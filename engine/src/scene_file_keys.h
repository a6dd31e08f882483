// The keys of a scene file, section by section (configs/README.md, "Scene files"): what
// scene_file.cpp reads, with the ranges it accepts and the help the documentation gives.
#pragma once

#include <rtwall/toml_reader.h>

namespace rtwall::scene_keys {

using namespace toml_reader;

inline constexpr Key kTopKeys[] = {
    {.name = "image", .type = KeyType::Table},
    {.name = "render", .type = KeyType::Table},
    {.name = "bvh", .type = KeyType::Table},
    {.name = "denoise", .type = KeyType::Table},
    {.name = "load", .type = KeyType::Table},
    {.name = "import", .type = KeyType::Table},
    {.name = "mesh", .type = KeyType::Tables},
    {.name = "material", .type = KeyType::Tables},
    {.name = "group", .type = KeyType::Tables},
    {.name = "instance", .type = KeyType::Tables},
    {.name = "light", .type = KeyType::Tables},
    {.name = "section", .type = KeyType::Tables},
    {.name = "camera", .type = KeyType::Tables},
    {.name = "parts", .type = KeyType::Table},
};

inline constexpr Key kImageKeys[] = {
    {.name = "width", .type = KeyType::Integer, .lo = 1, .hi = 16384, .help = "image width in pixels"},
    {.name = "height", .type = KeyType::Integer, .lo = 1, .hi = 16384, .help = "image height in pixels"},
    {.name = "tile", .type = KeyType::Integer, .lo = 1, .hi = 1024, .help = "edge of the square tiles the image is cut into"},
};

inline constexpr Key kRenderKeys[] = {
    {.name = "kernel", .type = KeyType::Choice, .choices = "packet, single", .help = "packet-traced kernel (`rtcIntersect4/8/16`, picked for the CPU) or single rays (`rtcIntersect1`); both give the same bytes"},
    {.name = "shading", .type = KeyType::Choice, .choices = "full, eyelight", .help = "`eyelight`: primary rays only, colour times the cosine to the viewer; for fast previews"},
    {.name = "max_depth", .type = KeyType::Integer, .lo = 1, .hi = 64, .help = "longest ray path; the primary ray is depth 1, each reflection or refraction adds one"},
    {.name = "supersample", .type = KeyType::Integer, .lo = 1, .hi = 16, .help = "n x n regular sub-pixel samples per pixel"},
    {.name = "shadows", .type = KeyType::Boolean, .help = "hard shadows from every light"},
    {.name = "background", .type = KeyType::Vec3, .help = "radiance of rays that hit nothing"},
    {.name = "ambient", .type = KeyType::Vec3, .help = "constant ambient light, multiplied by the diffuse colour"},
    {.name = "threads", .type = KeyType::Integer, .lo = 0, .hi = 1024, .help = "render threads; 0 means one per hardware thread"},
    {.name = "prune_threshold", .type = KeyType::Number, .lo = 0.0, .hi = 1.0, .help = "ray-tree pruning: a secondary ray whose throughput to its pixel sample is below this is not traced; 0 = exact (no pruning)"},
    {.name = "gi", .type = KeyType::Boolean, .help = "global illumination: path tracing with next-event estimation (docs/shading.md)"},
    {.name = "samples", .type = KeyType::Integer, .lo = 1, .hi = 4096, .help = "random samples per pixel sample and frame (GI paths, glossy metal, area lights)"},
    {.name = "view", .type = KeyType::Choice, .choices = "shaded, depth, rays, tile_time, client", .help = "false-colour views: deepest ray per pixel (red at 25), rays per pixel sample (log, red at 64), render time per tile (log, 0.1 ms blue to 100 ms red), the render client that made the tile"},
};

inline constexpr Key kBvhKeys[] = {
    {.name = "quality", .type = KeyType::Choice, .choices = "low, medium, high", .help = "Embree build quality of each mesh's BVH: low builds fastest, high (spatial splits) renders fastest and takes longest"},
    {.name = "compact", .type = KeyType::Boolean, .help = "`RTC_SCENE_FLAG_COMPACT`: less memory, slower rays"},
    {.name = "robust", .type = KeyType::Boolean, .help = "`RTC_SCENE_FLAG_ROBUST` on every BVH: conservative traversal, for thin CAD triangles (the generated power plant sets it)"},
    {.name = "primitives", .type = KeyType::Choice, .choices = "auto, triangles", .help = "what each mesh's BVH is built from. `auto`: consecutive triangles (2k, 2k+1) that share an edge go to Embree as one quad (`RTC_GEOMETRY_TYPE_QUAD`; the same two triangles, so the same picture to rounding), which gives a smaller BVH with half the leaves; a mesh where fewer than 3/4 of the pairs share an edge stays triangles. `triangles`: every triangle as it is"},
};

inline constexpr Key kDenoiseKeys[] = {
    {.name = "mode", .type = KeyType::Choice, .choices = "off, temporal, svgf", .help = "what the display side does with the frames of a stochastic scene (GI, area lights, glossy metal, volumes). `off`: a still view's frames are averaged, a moving view shows each frame's own samples. `temporal`: each pixel's history is re-projected from the frames before (rejected where depth, normal or object disagree) and averaged with the new frame. `svgf`: that, then an edge-avoiding a-trous wavelet filter of the illumination (docs/shading.md, \"Denoising\")"},
    {.name = "levels", .type = KeyType::Integer, .lo = 1, .hi = 10, .help = "a-trous iterations of `svgf`: the filter reaches 2^levels pixels"},
    {.name = "history", .type = KeyType::Integer, .lo = 1, .hi = 65536, .help = "the most frames a pixel of a moving view averages (its newest frame weighs at least 1/history); a still view averages all, as without a denoiser"},
    {.name = "sigma_depth", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "depth edge stop: neighbours whose depth differs by more than this times the local depth gradient weigh little"},
    {.name = "sigma_normal", .type = KeyType::Number, .lo = 0.0, .hi = 1e6, .help = "normal edge stop: a neighbour weighs its normals' cosine to this power"},
    {.name = "sigma_luminance", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "luminance edge stop: neighbours whose illumination differs by more than this many standard deviations of the noise weigh little"},
};

inline constexpr Key kLoadKeys[] = {
    {.name = "cache", .type = KeyType::Boolean, .help = "keep a binary cache of each imported mesh file and load it instead of parsing when it is current; a stale, corrupt or truncated cache is rebuilt"},
    {.name = "cache_dir", .type = KeyType::String, .help = "a folder for the caches (created)"},
};

inline constexpr Key kImportKeys[] = {
    {.name = "linear_deflection", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "the largest distance between a surface and its triangles, in the file's units (mm for most CAD files)"},
    {.name = "angular_deflection", .type = KeyType::Number, .lo = 1e-3, .hi = 3.14159, .help = "the largest angle between neighbouring triangles, radians"},
    {.name = "share_congruent", .type = KeyType::Boolean, .help = "assemblies (glTF, STEP, IGES): meshes that are the same shape up to a rigid motion are stored once, whatever the file declares (docs/assemblies.md); false keeps every mesh the file has"},
    {.name = "congruence_tolerance", .type = KeyType::Number, .lo = 1e-9, .hi = 1e-1, .help = "how far a vertex may lie from its congruent counterpart, as a fraction of the shape's bounding-box diagonal"},
};

inline constexpr Key kMeshKeys[] = {
    {.name = "name", .type = KeyType::String, .help = "how instances refer to it; unique"},
    {.name = "file", .type = KeyType::String, .help = "a mesh file: `.obj`, `.off`, `.ply` (ASCII or binary), `.stl` (ASCII or binary), `.om`, `.vtk` (legacy polydata or unstructured grid, ASCII or binary), `.vtp`, `.vtu` (XML: ASCII, base64, raw appended, zlib/LZ4 compressed; an unstructured grid becomes its outer surface), `.wrl` (VRML 2.0, through VTK). Per-vertex colours in the file multiply the material colour"},
    {.name = "shape", .type = KeyType::Choice, .choices = "sphere, box, quad, torus_knot", .help = "instead of `file`: `\"sphere\"`, `\"box\"`, `\"quad\"` or `\"torus_knot\"`"},
    {.name = "linear_deflection", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "STEP/IGES files only: this file's tessellation, over `[import]`'s"},
    {.name = "angular_deflection", .type = KeyType::Number, .lo = 1e-3, .hi = 3.14159, .help = "STEP/IGES files only: this file's tessellation, over `[import]`'s"},
};

inline constexpr Key kSphereKeys[] = {
    {.name = "rings", .type = KeyType::Integer, .lo = 2, .hi = 4096, .help = "sphere tessellation (defaults 32, 64)"},
    {.name = "segments", .type = KeyType::Integer, .lo = 3, .hi = 8192, .help = "sphere tessellation (defaults 32, 64)"},
};

inline constexpr Key kTorusKnotKeys[] = {
    {.name = "p", .type = KeyType::Integer, .lo = 1, .hi = 64, .help = "torus knot parameters (defaults 2, 3, 256, 16, 0.25)"},
    {.name = "q", .type = KeyType::Integer, .lo = 1, .hi = 64, .help = "torus knot parameters (defaults 2, 3, 256, 16, 0.25)"},
    {.name = "segments", .type = KeyType::Integer, .lo = 3, .hi = 1 << 20, .help = "sphere tessellation (defaults 32, 64)"},
    {.name = "sides", .type = KeyType::Integer, .lo = 3, .hi = 4096, .help = "torus knot parameters (defaults 2, 3, 256, 16, 0.25)"},
    {.name = "radius", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "torus knot parameters (defaults 2, 3, 256, 16, 0.25)"},
};

inline constexpr Key kMaterialKeys[] = {
    {.name = "name", .type = KeyType::String, .help = "unique"},
    {.name = "type", .type = KeyType::Choice, .choices = "lambert, phong, mirror, glass, metal, emissive, volume"},
    {.name = "texture", .type = KeyType::Choice, .choices = "checker, marble, wood, image", .help = "colour pattern; `color` is the first colour (multiplies images)"},
    {.name = "texture_file", .type = KeyType::String, .help = "PNG or JPEG, relative to the scene file"},
    {.name = "texture_color2", .type = KeyType::Vec3, .help = "checker: second colour; marble: veins; wood: rings"},
    {.name = "texture_scale", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "object units per repeat"},
    {.name = "texture_mapping", .type = KeyType::Choice, .choices = "auto, uv, xz, xy, yz, spherical, cylindrical", .help = "`\"uv\"`: the mesh's own texture coordinates (OBJ `vt`, PLY `u v`/`s t`/`texture_u texture_v`, OFF `ST`, VTK point TCoords, VRML `TextureCoordinate`), interpolated at the hit, divided by `texture_scale`; an instance whose mesh has none is an error naming the scene file, material and mesh. `\"auto\"`: `\"uv\"` where the hit mesh has texture coordinates, `\"xz\"` where it has none. The planar ones project the object-space position; marble and wood are solid textures (with uv they see the position (u, 0, v))"},
    {.name = "color", .type = KeyType::Vec3, .help = "diffuse albedo; mirror/metal reflectance; glass transmission tint; multiplies an image texture"},
    {.name = "roughness", .type = KeyType::Number, .lo = 0.0, .hi = 1.0, .help = "metal only: 0 is a perfect mirror; a Phong lobe of exponent 2/r² − 2 around the mirror direction"},
    {.name = "absorption", .type = KeyType::Vec3, .help = "glass only: Beer-Lambert absorption per unit of path length inside"},
    {.name = "emission", .type = KeyType::Vec3, .help = "radiance the surface emits from its front (found by camera and GI rays, not sampled as a light; on an area light it is the light's visible face, see `[[light]]`)"},
    {.name = "two_sided", .type = KeyType::Boolean, .help = "the emission leaves both sides; by default only the front, the side the triangles' winding faces (the `quad` shape faces +y), as area lights emit to one side. Not for volumes"},
    {.name = "bump", .type = KeyType::Number, .lo = 0.0, .hi = 100.0, .help = "bump mapping: amplitude of a noise height field (0 = off)"},
    {.name = "bump_scale", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "feature size of the bumps in object units (in (u, v) units with uv bumps)"},
    {.name = "bump_mapping", .type = KeyType::Choice, .choices = "auto, uv, object", .help = "`\"object\"`: the noise of the object-space position; `\"uv\"`: the noise of (u, v), turned into a normal by the triangle's tangent frame dP/du, dP/dv; `\"auto\"`: `\"uv\"` where the mesh has texture coordinates"},
    {.name = "alpha", .type = KeyType::Choice, .choices = "checker, marble, wood, image", .help = "alpha mask: where its red channel is below `alpha_cutoff` the surface is a hole, for every ray including shadow rays"},
    {.name = "alpha_file", .type = KeyType::String, .help = "as the `texture_*` keys, for the mask (a checker mask needs `alpha_color2 = [0, 0, 0]` for its holes)"},
    {.name = "alpha_color2", .type = KeyType::Vec3, .help = "as the `texture_*` keys, for the mask (a checker mask needs `alpha_color2 = [0, 0, 0]` for its holes)"},
    {.name = "alpha_scale", .type = KeyType::Number, .lo = 1e-6, .hi = 1e6, .help = "as the `texture_*` keys, for the mask (a checker mask needs `alpha_color2 = [0, 0, 0]` for its holes)"},
    {.name = "alpha_mapping", .type = KeyType::Choice, .choices = "auto, uv, xz, xy, yz, spherical, cylindrical", .help = "as the `texture_*` keys, for the mask (a checker mask needs `alpha_color2 = [0, 0, 0]` for its holes)"},
    {.name = "alpha_cutoff", .type = KeyType::Number, .lo = 0.0, .hi = 1.0, .help = "mask mode: alpha below it is a hole"},
    {.name = "alpha_channel", .type = KeyType::Choice, .choices = "red, alpha", .help = "what the mask reads: its red channel (default), or an image's alpha channel (1 for images without one and for the patterns)"},
    {.name = "alpha_mode", .type = KeyType::Choice, .choices = "mask, hashed", .help = "`\"mask\"`: a hole where alpha < `alpha_cutoff`; `\"hashed\"`: a ray keeps each hit with probability alpha (a hash of the ray and the triangle: deterministic), so accumulated samples converge to alpha blending (glTF's BLEND)"},
    {.name = "opacity", .type = KeyType::Number, .lo = 0.0, .hi = 1.0, .help = "multiplies the mask's alpha; without a mask it is the alpha (glTF's base colour alpha)"},
    {.name = "volume_file", .type = KeyType::String, .help = "VTK image data: `.vti` or legacy `.vtk` structured points; the first point-data array; it fills the instance mesh's bounding box"},
    {.name = "volume_step", .type = KeyType::Number, .lo = 0.01, .hi = 100.0, .help = "ray-march step in voxels (speed/accuracy)"},
    {.name = "transfer", .type = KeyType::Points, .help = "transfer function, linear between points: colour sent to the eye, extinction per object unit"},
    {.name = "specular", .type = KeyType::Vec3, .help = "phong only: specular reflectance (normalised Blinn-Phong)"},
    {.name = "shininess", .type = KeyType::Number, .lo = 1.0, .hi = 1e5, .help = "phong only: Blinn-Phong exponent"},
    {.name = "ior", .type = KeyType::Number, .lo = 1.0, .hi = 4.0, .help = "glass only: index of refraction; Fresnel reflection and total internal reflection follow from it"},
};

inline constexpr Key kInstanceKeys[] = {
    {.name = "mesh", .type = KeyType::String, .help = "a `[[mesh]]` name"},
    {.name = "group", .type = KeyType::String, .help = "instead of `mesh`: a `[[group]]` name; exactly one of `mesh` and `group`"},
    {.name = "material", .type = KeyType::String, .help = "a `[[material]]` name; for a group, the material of every member that names none"},
    {.name = "scale", .type = KeyType::Scale, .lo = 1e-12, .hi = 1e12, .help = "applied first; no zero factors"},
    {.name = "rotate", .type = KeyType::Vec3d, .help = "applied second: about x, then y, then z"},
    {.name = "translate", .type = KeyType::Vec3d, .help = "applied last"},
    {.name = "movable", .type = KeyType::Boolean, .help = "a part the review will move (a valve, a door): kept in the small top level of moving instances from the start, so that moving it never rebuilds the static rest of the scene (what an unmarked part pays on its first move, in the background); for a group or an assembly, every instance it expands to. Images are the same either way"},
};

inline constexpr Key kGroupKeys[] = {
    {.name = "name", .type = KeyType::String},
    {.name = "instance", .type = KeyType::Tables},
};

inline constexpr Key kLightKeys[] = {
    {.name = "type", .type = KeyType::Choice, .choices = "point, directional, area"},
    {.name = "position", .type = KeyType::Vec3d, .help = "area: one corner"},
    {.name = "edge1", .type = KeyType::Vec3, .help = "the parallelogram's edges; it emits towards cross(edge1, edge2) only"},
    {.name = "edge2", .type = KeyType::Vec3, .help = "the parallelogram's edges; it emits towards cross(edge1, edge2) only"},
    {.name = "direction", .type = KeyType::Vec3, .help = "the direction the light travels"},
    {.name = "two_sided", .type = KeyType::Boolean, .help = "area lights only: emit to both sides of the parallelogram (a point or directional light with it is an error)"},
    {.name = "color", .type = KeyType::Vec3},
    {.name = "intensity", .type = KeyType::Number, .lo = 0.0, .hi = 1e12, .help = "point: radiant intensity, irradiance falls off as intensity / distance²; directional: irradiance; area: radiance"},
};

inline constexpr Key kSectionKeys[] = {
    {.name = "point", .type = KeyType::Vec3d, .help = "a point on the plane, in the file's coordinates (double precision, rebased with the scene: see above)"},
    {.name = "normal", .type = KeyType::Vec3, .help = "points towards the side that is **kept**; need not be unit length"},
    {.name = "cap_color", .type = KeyType::Vec3, .help = "the cap's albedo (linear)"},
    {.name = "caps", .type = KeyType::Boolean, .help = "false: the cut stays open and the insides of parts show through it"},
    {.name = "enabled", .type = KeyType::Boolean, .help = "a disabled plane cuts nothing; on the wall it can be turned on (V)"},
};

inline constexpr Key kCameraKeys[] = {
    {.name = "name", .type = KeyType::String, .help = "chosen with `rtwall render --camera NAME`; the first camera is the default"},
    {.name = "position", .type = KeyType::Vec3d},
    {.name = "look_at", .type = KeyType::Vec3d},
    {.name = "up", .type = KeyType::Vec3, .help = "must not be parallel to the viewing direction"},
    {.name = "fov", .type = KeyType::Number, .lo = 0.01, .hi = 179.0, .help = "vertical field of view in degrees"},
};

inline constexpr Key kPartsKeys[] = {
    {.name = "hide", .type = KeyType::Strings, .help = "these are not rendered: no pixels, shadows, reflections"},
    {.name = "isolate", .type = KeyType::Strings, .help = "only these are rendered"},
    {.name = "highlight", .type = KeyType::Strings, .help = "tinted orange and glowing (the colour change [docs/design-review.md](../docs/design-review.md#parts-hide-isolate-highlight) states)"},
};

inline constexpr Section kTop{"the scene file", "# Scene files", kTopKeys};
inline constexpr Section kImage{"[image]", "## `[image]`", kImageKeys};
inline constexpr Section kRender{"[render]", "## `[render]`", kRenderKeys};
inline constexpr Section kBvh{"[bvh]", "## `[bvh]`", kBvhKeys};
inline constexpr Section kDenoise{"[denoise]", "## `[denoise]`", kDenoiseKeys};
inline constexpr Section kLoad{"[load]", "## `[load]`", kLoadKeys};
inline constexpr Section kImport{"[import]", "## `[import]`", kImportKeys};
inline constexpr Section kMesh{"[[mesh]]", "## `[[mesh]]`", kMeshKeys};
// A shape's parameters: a [[mesh]] with that shape reads them (Reader::extend).
inline constexpr Section kSphere{"[[mesh]] sphere", "## `[[mesh]]`", kSphereKeys};
inline constexpr Section kTorusKnot{"[[mesh]] torus_knot", "## `[[mesh]]`", kTorusKnotKeys};
inline constexpr Section kMaterial{"[[material]]", "## `[[material]]`", kMaterialKeys};
// [[group.instance]] has the same keys.
inline constexpr Section kInstance{"[[instance]]", "## `[[instance]]`", kInstanceKeys};
inline constexpr Section kGroup{"[[group]]", "## `[[group]]`", kGroupKeys};
inline constexpr Section kLight{"[[light]]", "## `[[light]]`", kLightKeys};
inline constexpr Section kSection{"[[section]]", "## `[[section]]`", kSectionKeys};
inline constexpr Section kCamera{"[[camera]]", "## `[[camera]]`", kCameraKeys};
inline constexpr Section kParts{"[parts]", "## `[parts]`", kPartsKeys};

// Every section, for the test that holds them against the documentation.
inline constexpr const Section* kAll[] = {&kTop,      &kImage,    &kRender,   &kBvh,      &kLoad,  &kImport,
                                          &kMesh,     &kSphere,   &kTorusKnot, &kMaterial, &kInstance, &kGroup,
                                          &kLight,    &kSection,  &kCamera,   &kParts, &kDenoise};

}  // namespace rtwall::scene_keys
