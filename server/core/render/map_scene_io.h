#pragma once
// The picture's scene from a map folder written by `objmap map --out` or `objmap export`:
// map.bt (the structure) and objects.json with its inventory objects' models
// (objects/<id>_<class>.ply).

#include <string>

#include "render/map_picture.h"

namespace objmap {

/// Reads `dir`'s map.bt (at its own resolution) and its inventory objects. False with the reason,
/// naming the file, when one is missing or unreadable; a folder without map.bt is an error, one
/// without objects is not.
[[nodiscard]] bool ReadMapScene(const std::string& dir, PictureScene* scene, std::string* why);

}  // namespace objmap
