// Sections of a wall config read in files of their own; wall_config.cpp reads the rest and the
// layout as a whole. Each reads its table with the Reader of that table (its keys from
// wall_config_keys.h) and fails with the file, line and key as every wall config error does.
#pragma once

#include "wall_config_keys.h"

#include <rtwall/display.h>

namespace rtwall {

// [tracking] (wall_config_room.cpp): the source, the room transform, the filter and the flystick.
void readTracking(toml_reader::Reader& r, TrackingConfig& tracking);
// [navigation] (wall_config_room.cpp): the room's scale in the scene.
void readNavigation(toml_reader::Reader& r, NavigationConfig& navigation);

}  // namespace rtwall
