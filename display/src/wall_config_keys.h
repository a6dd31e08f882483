// The keys of a wall config, section by section (configs/README.md, "Wall configs"): what
// wall_config.cpp reads, with the ranges it accepts and the help the documentation gives.
#pragma once

#include <rtwall/toml_reader.h>

namespace rtwall::wall_keys {

using namespace toml_reader;

inline constexpr Key kTopKeys[] = {
    {.name = "wall", .type = KeyType::Table},
    {.name = "stereo", .type = KeyType::Table},
    {.name = "tracking", .type = KeyType::Table},
    {.name = "navigation", .type = KeyType::Table},
    {.name = "grid", .type = KeyType::Table},
    {.name = "screen", .type = KeyType::Tables},
    {.name = "node", .type = KeyType::Tables},
    {.name = "headless", .type = KeyType::Table},
    {.name = "warp", .type = KeyType::Table},
};

inline constexpr Key kWallKeys[] = {
    {.name = "name", .type = KeyType::String, .help = "shown in window titles"},
    {.name = "width", .type = KeyType::Integer, .lo = 1, .hi = 65536, .help = "the wall image in pixels; *required* with `[[screen]]`; with `[grid]` it must match if given"},
    {.name = "height", .type = KeyType::Integer, .lo = 1, .hi = 65536, .help = "the wall image in pixels; *required* with `[[screen]]`; with `[grid]` it must match if given"},
    {.name = "vsync", .type = KeyType::Boolean, .help = "swap on the retrace (the first window waits; all windows are swapped together)"},
    {.name = "swap_group", .type = KeyType::Integer, .lo = 0, .hi = 1 << 20, .help = "join this PC's windows to `GLX_NV_swap_group` group N (they swap together in the driver), where the driver has the extension (NVIDIA Quadro/RTX A-series on X11); where it has not, one line says so and the windows swap as without it"},
    {.name = "reproject", .type = KeyType::Choice, .choices = "off, on", .help = "re-projection ([docs/latency.md](../docs/latency.md)): every refresh shows the newest rendered frame warped to the head pose read just before the swap, so the wall follows the head at the display's rate whatever the render rate (the clients send depth with every tile); off: each rendered frame is shown once, as rendered. Default: on for a tracked wall, else off"},
    {.name = "reproject_debug", .type = KeyType::Boolean, .help = "with re-projection: tint each pixel by where it came from (green: rendered for this pose, blue: warped, yellow: filled from the frame before, red: filled from its row); the `J` key toggles it"},
    {.name = "refresh_hz", .type = KeyType::Number, .lo = 1.0, .hi = 1000.0, .help = "with re-projection: presentations a second where no retrace paces them (headless, or `vsync = false`); default 60"},
    {.name = "swap_barrier", .type = KeyType::Integer, .lo = 0, .hi = 1 << 20, .help = "with `swap_group`: bind the group to `GLX_NV_swap_barrier` N, so that the groups of all PCs wired to one frame-lock board (Quadro Sync) swap together in hardware, on top of the master's network barrier"},
};

inline constexpr Key kStereoKeys[] = {
    {.name = "mode", .type = KeyType::Choice, .choices = "none, passive, side_by_side, quad_buffer", .help = "passive: one screen per eye (`eye = \"left\"`/`\"right\"`); side-by-side: each screen shows the left eye in its left half; quad-buffer: `GL_BACK_LEFT`/`GL_BACK_RIGHT` where the driver has it"},
    {.name = "eye_separation", .type = KeyType::Number, .lo = 0.0, .hi = 1.0, .help = "metres of the room (`[navigation]` `scale` scene units each)"},
    {.name = "viewer", .type = KeyType::Vec3, .help = "the viewer's head, wall coordinates"},
    {.name = "lower_left", .type = KeyType::Vec3, .help = "the wall's physical corners; must span a rectangle"},
    {.name = "lower_right", .type = KeyType::Vec3, .help = "the wall's physical corners; must span a rectangle"},
    {.name = "upper_left", .type = KeyType::Vec3, .help = "the wall's physical corners; must span a rectangle"},
};

inline constexpr Key kTrackingKeys[] = {
    {.name = "source", .type = KeyType::String, .help = "the IPv4 address to listen on (`0.0.0.0`: every interface) and the UDP port DTrack sends to (0: a free port, printed at start; for tests); `\"vrpn\"`: a VRPN server (`server`), [docs/tracking.md](../docs/tracking.md)"},
    {.name = "server", .type = KeyType::String, .help = "the VRPN device and server (port 3883 unless given)"},
    {.name = "buttons", .type = KeyType::String, .help = "VRPN: the `vrpn_Button` and `vrpn_Analog` devices on that server giving the wand's buttons and joystick"},
    {.name = "analog", .type = KeyType::String, .help = "VRPN: the `vrpn_Button` and `vrpn_Analog` devices on that server giving the wand's buttons and joystick"},
    {.name = "head_body", .type = KeyType::Integer, .lo = 0, .hi = 1'000'000, .help = "the DTrack id of the 6DOF body on the viewer's head (its x axis runs from the left eye to the right)"},
    {.name = "flystick", .type = KeyType::Integer, .lo = -1, .hi = 255, .help = "the DTrack id of the Flystick (`6df2`); -1: none"},
    {.name = "room_scale", .type = KeyType::Number, .lo = 1e-09, .hi = 1000000.0, .help = "tracker units to metres (DTrack sends millimetres, VRPN metres)"},
    {.name = "room_rotate", .type = KeyType::Vec3d, .help = "the tracker's room axes into wall axes: about x, then y, then z (`[-90, 0, 0]` turns DTrack's usual z-up room into the wall's y-up)"},
    {.name = "room_translate", .type = KeyType::Vec3d, .help = "where the tracker's origin lies in wall coordinates (applied last)"},
    {.name = "timeout_ms", .type = KeyType::Integer, .lo = 1, .hi = 60'000, .help = "no datagram with the head for this long: the last pose is held and the status overlay says so"},
    {.name = "prediction_ms", .type = KeyType::Number, .lo = 0.0, .hi = 500.0, .help = "constant-velocity prediction of the head this far ahead (the motion-to-photon latency); 0: off"},
    {.name = "filter", .type = KeyType::Choice, .choices = "none, one_euro", .help = "smoothing of the head's and the wand's position and orientation (one-euro filter: little lag when moving, little jitter when still)"},
    {.name = "min_cutoff", .type = KeyType::Number, .lo = 0.001, .hi = 1000.0, .help = "one-euro: the cutoff frequency of a still head (lower: smoother, more lag)"},
    {.name = "beta", .type = KeyType::Number, .lo = 0.0, .hi = 1000000.0, .help = "one-euro: cutoff added per m/s of head speed (higher: less lag when moving)"},
    {.name = "derivative_cutoff", .type = KeyType::Number, .lo = 0.001, .hi = 1000.0, .help = "one-euro: the cutoff of the speed estimate"},
    {.name = "button_pick", .type = KeyType::Integer, .lo = -1, .hi = 255, .help = "the Flystick button that picks and drags (held) or sets a measure point; -1: none"},
    {.name = "button_mode", .type = KeyType::Integer, .lo = -1, .hi = 255, .help = "the button that switches fly and orbit"},
    {.name = "button_home", .type = KeyType::Integer, .lo = -1, .hi = 255, .help = "the button that goes back to the start camera"},
    {.name = "joystick_x", .type = KeyType::Integer, .lo = -1, .hi = 255, .help = "the controllers (DTrack) or analog channels (VRPN) of the joystick's axes"},
    {.name = "joystick_y", .type = KeyType::Integer, .lo = -1, .hi = 255, .help = "the controllers (DTrack) or analog channels (VRPN) of the joystick's axes"},
    {.name = "fly_speed", .type = KeyType::Number, .lo = 0.0, .hi = 1000000.0, .help = "speed at full deflection, in metres of the room a second (times `[navigation]` `scale` in scene units)"},
    {.name = "turn_speed", .type = KeyType::Number, .lo = 0.0, .hi = 3600.0, .help = "turning speed at full deflection"},
    {.name = "dead_zone", .type = KeyType::Number, .lo = 0.0, .hi = 0.99, .help = "joystick deflections below this count as none"},
    {.name = "wand_direction", .type = KeyType::Vec3d, .help = "where the wand points, in its body's axes (ART's Flystick: -z)"},
    {.name = "wand_ray", .type = KeyType::Boolean, .help = "draw the wand's ray on the wall"},
};

inline constexpr Key kNavigationKeys[] = {
    {.name = "scale", .type = KeyType::Number, .lo = 1e-06, .hi = 1000000.0, .help = "scene units per metre of the room (the wall's corners, the viewer, the tracked head and wand, `eye_separation`, `fly_speed`): 1 shows the scene life-size in scene units of metres; 1000 shows a model in millimetres life-size; 2 makes the viewer a giant to whom the world looks half its size. The keys `[` and `]` change it at run time, about the head"},
};

inline constexpr Key kGridKeys[] = {
    {.name = "columns", .type = KeyType::Integer, .lo = 1, .hi = 64},
    {.name = "rows", .type = KeyType::Integer, .lo = 1, .hi = 64},
    {.name = "screen_width", .type = KeyType::Integer, .lo = 1, .hi = 16384, .help = "each screen's visible pixels"},
    {.name = "screen_height", .type = KeyType::Integer, .lo = 1, .hi = 16384, .help = "each screen's visible pixels"},
    {.name = "bezel", .type = KeyType::Integers, .lo = 0, .hi = 16384, .help = "hidden pixels at each edge: between two screens `right + left` wall pixels are rendered but not shown, so lines crossing a bezel stay straight"},
    {.name = "bezel_mm", .type = KeyType::Numbers, .lo = 0.0, .hi = 10000.0, .help = "instead of `bezel`, with `screen_mm`"},
    {.name = "screen_mm", .type = KeyType::Integers, .lo = 1, .hi = 100000, .help = "the visible area, to turn `bezel_mm` into pixels"},
    {.name = "overlap", .type = KeyType::Integer, .lo = 0, .hi = 16384, .help = "projectors: neighbours overlap by this many pixels, with blending ramps of that width on the inner edges (no bezels then)"},
    {.name = "blend_gamma", .type = KeyType::Numbers, .lo = 0.1, .hi = 10.0, .help = "as for `[[screen]]`, for every screen"},
    {.name = "gamma", .type = KeyType::Number, .lo = 0.1, .hi = 10.0, .help = "as for `[[screen]]`, for every screen"},
    {.name = "brightness", .type = KeyType::Number, .lo = 0.0, .hi = 10.0, .help = "as for `[[screen]]`, for every screen"},
    {.name = "fullscreen", .type = KeyType::Boolean, .help = "as for `[[screen]]`, for every screen"},
    {.name = "first_monitor", .type = KeyType::Integer, .lo = 0, .hi = 64, .help = "screen i (row-major) uses GLFW monitor `first_monitor + i` when fullscreen"},
};

inline constexpr Key kScreenKeys[] = {
    {.name = "name", .type = KeyType::String, .help = "unique; names the headless output files"},
    {.name = "viewport", .type = KeyType::Integers, .lo = 0, .hi = 65536, .help = "the wall pixels this screen shows; inside the wall"},
    {.name = "resolution", .type = KeyType::Integers, .lo = 1, .hi = 16384, .help = "the screen's own pixels (scaled, nearest pixel)"},
    {.name = "blend", .type = KeyType::Integers, .lo = 0, .hi = 16384, .help = "blending ramp widths in wall pixels: over the ramp the light falls linearly to 0 at the edge"},
    {.name = "blend_gamma", .type = KeyType::Numbers, .lo = 0.1, .hi = 10.0, .help = "the display gamma the ramp compensates: the pixel value is multiplied by ramp^(1/gamma)"},
    {.name = "gamma", .type = KeyType::Number, .lo = 0.1, .hi = 10.0, .help = "colour correction: out = brightness · in^(1/gamma)"},
    {.name = "brightness", .type = KeyType::Number, .lo = 0.0, .hi = 10.0},
    {.name = "fullscreen", .type = KeyType::Boolean},
    {.name = "eye", .type = KeyType::Choice, .choices = "mono, left, right, both"},
    {.name = "monitor", .type = KeyType::Integer, .lo = 0, .hi = 64, .help = "GLFW monitor when `fullscreen`"},
    {.name = "window", .type = KeyType::Integers, .lo = -65536, .hi = 65536, .help = "window position when windowed"},
    {.name = "shader", .type = KeyType::String, .help = "a fragment shader file (relative to the config) instead of `present.frag`; it gets the same uniforms and is compiled with glslang by `rtwall check`"},
    {.name = "lower_left", .type = KeyType::Vec3, .help = "the screen's physical corners in wall coordinates, for screens that are not one rectangle (a CAVE, an angled wall); all three on every screen or on none"},
    {.name = "lower_right", .type = KeyType::Vec3, .help = "the screen's physical corners in wall coordinates, for screens that are not one rectangle (a CAVE, an angled wall); all three on every screen or on none"},
    {.name = "upper_left", .type = KeyType::Vec3, .help = "the screen's physical corners in wall coordinates, for screens that are not one rectangle (a CAVE, an angled wall); all three on every screen or on none"},
    {.name = "node", .type = KeyType::String, .help = "the display node (wall PC) that drives the screen: 1 to 32 letters, digits, `-`, `_`; on every screen or on none (see [Display nodes](#display-nodes))"},
};

inline constexpr Key kNodeKeys[] = {
    {.name = "name", .type = KeyType::String, .help = "the node's name (1 to 32 letters, digits, `-`, `_`); one `[[node]]` per node"},
    {.name = "columns", .type = KeyType::Integers, .lo = 0, .hi = 63, .help = "the grid columns (from 0, inclusive) whose screens the node drives"},
    {.name = "rows", .type = KeyType::Integers, .lo = 0, .hi = 63, .help = "the grid rows likewise"},
};

inline constexpr Key kHeadlessKeys[] = {
    {.name = "write_every", .type = KeyType::Integer, .lo = 0, .hi = 100'000'000, .help = "without a display, every Nth frame is written per screen as `frame_NNNNNN_<screen>.png` (what each projector would get; 0: never)"},
    {.name = "video", .type = KeyType::String, .help = "also pipe the wall image to the `ffmpeg` program (when installed) into this file in the output folder"},
};

inline constexpr Key kWarpKeys[] = {
    {.name = "mpcdi", .type = KeyType::String, .help = "the projector calibration: a VESA MPCDI file (`.mpcdi`, [docs/mpcdi.md](../docs/mpcdi.md)), relative to the config; *required*"},
    {.name = "buffers", .type = KeyType::Table, .help = "each MPCDI buffer id to the screen it drives, e.g. `{ proj0 = \"left\", proj1 = \"right\" }`: the buffer's pixels are the screen's; every buffer of the file mapped, each screen at most once; *required*"},
    {.name = "mode", .type = KeyType::Choice, .choices = "direct, post", .help = "direct (default): each projector pixel's ray goes from the eye through the point of the screen surface the calibration gives it; post: the screen's flat image is resampled through the warp after rendering (the rasteriser's way, for comparison)"},
    {.name = "region_y", .type = KeyType::Choice, .choices = "top, bottom", .help = "where the file's regions lie in their buffers: `y` counted from the buffer's top (default, as nDisplay reads it) or from its bottom (as SGCT does); the readers disagree, so a region of a partial buffer may need this"},
    {.name = "eyepoint", .type = KeyType::Vec3, .help = "profile `3d` (3D simulation): the calibration's eye point, the apex of its regions' frusta, in room coordinates, metres. Default: `[stereo] viewer`"},
    {.name = "frustum_distance", .type = KeyType::Number, .help = "profile `3d`: each projector pixel's ray is fixed as the point at this distance (metres, along the frustum's axis) in its frustum direction from the eye point; a tracked or stereo eye looks through those points (SGCT's way). Default 10"},
};

inline constexpr Section kTop{"the wall config", "# Wall configs", kTopKeys};
inline constexpr Section kWall{"[wall]", "## `[wall]`", kWallKeys};
inline constexpr Section kStereo{"[stereo]", "## `[stereo]`", kStereoKeys};
inline constexpr Section kTracking{"[tracking]", "## `[tracking]`", kTrackingKeys};
inline constexpr Section kNavigation{"[navigation]", "## `[navigation]`", kNavigationKeys};
inline constexpr Section kGrid{"[grid]", "## `[grid]`", kGridKeys};
inline constexpr Section kScreen{"[[screen]]", "## `[[screen]]`", kScreenKeys};
inline constexpr Section kNode{"[[node]]", "## Display nodes", kNodeKeys};
inline constexpr Section kHeadless{"[headless]", "## `[headless]`", kHeadlessKeys};
inline constexpr Section kWarp{"[warp]", "## `[warp]`", kWarpKeys};

// Every section, for the test that holds them against the documentation.
inline constexpr const Section* kAll[] = {&kTop, &kWall, &kStereo, &kTracking, &kNavigation, &kGrid, &kScreen, &kNode, &kHeadless, &kWarp};

}  // namespace rtwall::wall_keys
