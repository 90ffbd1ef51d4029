#pragma once
// Real furniture meshes from Debian's sweethome3d-furniture: /usr/share/sweethome3d/furniture/
// *.sh3f are zip archives of OBJ/MTL models (CC-0 / CC-BY, credits in each archive) listed in a
// PluginFurnitureCatalog.properties (name#N, category#N, model#N, width#N / depth#N / height#N in
// cm, modelRotation#N, creator#N).

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "sim/scene.h"

namespace objmap::sim {

struct FurnitureEntry {
  std::string archive;  ///< the .sh3f file
  std::string name;     ///< "Coffee cup"
  std::string category;
  std::string model;  ///< path of the OBJ inside the archive
  std::string creator;
  Eigen::Vector3f size_m = Eigen::Vector3f::Zero();  ///< width, depth, height
  Eigen::Matrix3f model_rotation = Eigen::Matrix3f::Identity();
};

/// Thread-safety: const methods may run concurrently (each opens the archive itself).
class FurnitureCatalog {
 public:
  /// The default folder of Debian's package.
  static constexpr const char* kDefaultFolder = "/usr/share/sweethome3d/furniture";

  /// Reads the catalogs of every .sh3f in `folder`; nullptr with a reason when there is none.
  static std::unique_ptr<FurnitureCatalog> Open(const std::string& folder, std::string* why);

  [[nodiscard]] const std::vector<FurnitureEntry>& entries() const { return entries_; }
  /// Entries whose name is one of `names` exactly, in catalog order.
  [[nodiscard]] std::vector<const FurnitureEntry*> Named(
      const std::vector<std::string>& names) const;

  /// The entry's model as triangles in objmap's object frame: z up, the front facing -y,
  /// centred on x = y = 0, standing on z = 0, scaled to the entry's size. A triangle's colour is
  /// its material's diffuse colour, or its texture at the triangle's centre.
  [[nodiscard]] bool LoadMesh(const FurnitureEntry& entry, TriangleMesh* mesh,
                              std::string* why) const;

 private:
  std::vector<FurnitureEntry> entries_;
};

}  // namespace objmap::sim
