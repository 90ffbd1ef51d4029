#pragma once
// What the web viewer shows: a live MapServer or a map folder written by `objmap map`, behind one
// read-only interface, so that the HTTP side does not know which it serves.

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "map_server/map_server.h"

namespace objmap::http_viewer {

/// The read-only queries the viewer makes. Thread-safety: every method may be called from any
/// thread at any time (the HTTP server answers requests on several threads).
class ViewerMap {
 public:
  virtual ~ViewerMap() = default;

  /// What is shown, for the page title ("objmap_server map.db", "map folder out/redkitchen").
  [[nodiscard]] virtual std::string Description() const = 0;
  /// The current objects and inventory (never null).
  [[nodiscard]] virtual std::shared_ptr<const MapSnapshot> Snapshot() const = 0;
  /// Centres of occupied voxels, at most `max_count` (a larger map thinned evenly), and the
  /// voxel size.
  [[nodiscard]] virtual ServiceStatus StructureCenters(std::size_t max_count,
                                                       std::vector<Eigen::Vector3d>* centers,
                                                       double* voxel_size_m,
                                                       std::uint64_t* version) const = 0;
  /// Keyframe `id`'s colour image; kNotFound for an unknown id or a keyframe without one.
  [[nodiscard]] virtual ServiceStatus KeyframeColor(KeyframeId id, ColorImage* color) const = 0;
  /// As MapServer::IsFree.
  [[nodiscard]] virtual ServiceStatus IsFree(const Eigen::Vector3d& min_W,
                                             const Eigen::Vector3d& max_W, bool unknown_is_free,
                                             bool* free, RegionOccupancy* counts,
                                             std::vector<ObjectId>* objects_inside,
                                             std::uint64_t* version) const = 0;
  /// As MapServer::ChangesSince: changes after `since_version`, waiting up to `timeout` for one.
  [[nodiscard]] virtual std::vector<MapChange> ChangesSince(
      std::uint64_t since_version, std::chrono::milliseconds timeout) const = 0;
  /// The world's up direction from the keyframe cameras (held upright: UpFromCameras), so that
  /// the view orbits about it; nullopt when the poses do not tell.
  [[nodiscard]] virtual std::optional<Eigen::Vector3d> Up() const = 0;
};

/// A running MapServer, live: the viewer follows its keyframes and regenerations.
class LiveViewerMap final : public ViewerMap {
 public:
  /// `server` must outlive this.
  LiveViewerMap(const MapServer& server, std::string description);

  [[nodiscard]] std::string Description() const override;
  [[nodiscard]] std::shared_ptr<const MapSnapshot> Snapshot() const override;
  [[nodiscard]] ServiceStatus StructureCenters(std::size_t max_count,
                                               std::vector<Eigen::Vector3d>* centers,
                                               double* voxel_size_m,
                                               std::uint64_t* version) const override;
  [[nodiscard]] ServiceStatus KeyframeColor(KeyframeId id, ColorImage* color) const override;
  [[nodiscard]] ServiceStatus IsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                     bool unknown_is_free, bool* free, RegionOccupancy* counts,
                                     std::vector<ObjectId>* objects_inside,
                                     std::uint64_t* version) const override;
  [[nodiscard]] std::vector<MapChange> ChangesSince(
      std::uint64_t since_version, std::chrono::milliseconds timeout) const override;
  /// From the first keyframes' current poses.
  [[nodiscard]] std::optional<Eigen::Vector3d> Up() const override;

 private:
  const MapServer& server_;
  std::string description_;
};

/// A map folder written by `objmap map --out DIR`: map.bt, objects.json with objects/*.ply,
/// keyframes.txt (the poses) and keyframes/<id>.jpg for the crops. It does not change while shown.
class FolderViewerMap final : public ViewerMap {
 public:
  /// Reads the folder; nullptr with the reason (naming the file) when map.bt or objects.json is
  /// missing or unreadable. Keyframe images are read when asked for.
  static std::unique_ptr<FolderViewerMap> Open(const std::string& dir, std::string* why);
  ~FolderViewerMap() override;

  [[nodiscard]] std::string Description() const override;
  [[nodiscard]] std::shared_ptr<const MapSnapshot> Snapshot() const override;
  [[nodiscard]] ServiceStatus StructureCenters(std::size_t max_count,
                                               std::vector<Eigen::Vector3d>* centers,
                                               double* voxel_size_m,
                                               std::uint64_t* version) const override;
  [[nodiscard]] ServiceStatus KeyframeColor(KeyframeId id, ColorImage* color) const override;
  [[nodiscard]] ServiceStatus IsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                     bool unknown_is_free, bool* free, RegionOccupancy* counts,
                                     std::vector<ObjectId>* objects_inside,
                                     std::uint64_t* version) const override;
  /// A folder never changes: waits `timeout` and returns nothing.
  [[nodiscard]] std::vector<MapChange> ChangesSince(
      std::uint64_t since_version, std::chrono::milliseconds timeout) const override;
  /// From keyframes.txt, when the folder has it.
  [[nodiscard]] std::optional<Eigen::Vector3d> Up() const override;

 private:
  FolderViewerMap();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap::http_viewer
