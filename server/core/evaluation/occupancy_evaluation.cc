// The OctoMap scored against the surface the sensor saw: voxel keys in hash sets, neighbourhoods
// of one or two voxels, and the map's own state at each surface voxel.
#include <cstddef>

#include "evaluation/evaluation.h"
#include "evaluation/voxel_set.h"
#include "occupancy/occupancy_map.h"

namespace objmap {
namespace {

double Share(std::size_t part, std::size_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
}

}  // namespace

double OccupancyEvaluation::OccupiedPrecision() const {
  return Share(occupied_on_surface, occupied);
}
double OccupancyEvaluation::StructureCompleteness() const {
  return Share(structure_occupied, structure_surface);
}
double OccupancyEvaluation::StructureFreeShare() const {
  return Share(structure_free, structure_surface);
}
double OccupancyEvaluation::ObjectFreeShare() const { return Share(object_free, object_surface); }

OccupancyEvaluation EvaluateOccupancy(const OccupancyMap& map, const SeenSurface& surface) {
  OccupancyEvaluation result;
  const double voxel = map.config().resolution_m;
  result.voxel_size_m = voxel;
  VoxelSet seen(voxel);
  for (const auto* part : {&surface.structure_W, &surface.objects_W}) {
    for (const Eigen::Vector3f& p : *part) seen.Insert(p.cast<double>());
  }
  VoxelSet occupied(voxel);
  for (const Eigen::Vector3d& centre : map.OccupiedVoxelCenters()) {
    occupied.Insert(centre);
    ++result.occupied;
    if (seen.HasWithin(centre, 1)) {
      ++result.occupied_on_surface;
      ++result.occupied_near_surface;
    } else if (seen.HasWithin(centre, 2)) {
      ++result.occupied_near_surface;
    }
  }
  for (const Eigen::Vector3f& p : surface.structure_W) {
    ++result.structure_surface;
    if (occupied.HasWithin(p.cast<double>(), 1)) ++result.structure_occupied;
    if (map.Query(p.cast<double>()) == VoxelState::kFree) ++result.structure_free;
  }
  for (const Eigen::Vector3f& p : surface.objects_W) {
    ++result.object_surface;
    if (map.Query(p.cast<double>()) == VoxelState::kFree) ++result.object_free;
  }
  return result;
}

}  // namespace objmap
