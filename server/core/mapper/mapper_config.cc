// Validation of the Mapper's config structs (mapper.h).

#include <string>

#include "mapper/mapper.h"

namespace objmap {

bool ReassociationConfig::IsValid(std::string* why) const {
  if (!(min_translation_m >= 0.f) || !(min_rotation_rad >= 0.f)) {
    *why = "ReassociationConfig: min_translation_m and min_rotation_rad must be >= 0";
    return false;
  }
  return true;
}

bool RegenerationConfig::IsValid(std::string* why) const {
  if (threads < 1 || threads > 64) {
    *why = "RegenerationConfig: threads must lie in [1, 64]";
    return false;
  }
  if (!(incremental_max_moved_fraction >= 0.f && incremental_max_moved_fraction <= 1.f)) {
    *why = "RegenerationConfig: incremental_max_moved_fraction must lie in [0, 1]";
    return false;
  }
  return true;
}

bool UnknownObjectConfig::IsValid(std::string* why) const {
  if (min_segment_px < 1 || image_border_px < 0) {
    *why = "UnknownObjectConfig: min_segment_px must be >= 1 and image_border_px >= 0";
    return false;
  }
  if (!(max_claimed_fraction >= 0.f && max_claimed_fraction <= 1.f)) {
    *why = "UnknownObjectConfig: max_claimed_fraction must be in [0, 1]";
    return false;
  }
  if (!(max_support_gap_m >= 0.f) || !(min_height_m >= 0.f)) {
    *why = "UnknownObjectConfig: max_support_gap_m and min_height_m must be >= 0";
    return false;
  }
  if (!(min_extent_m >= 0.f && min_extent_m <= max_extent_m)) {
    *why = "UnknownObjectConfig: min_extent_m must be >= 0 and <= max_extent_m";
    return false;
  }
  return true;
}

bool MapperConfig::IsValid(std::string* why) const {
  if (!unknown_objects.IsValid(why)) return false;
  if (!segmenter.IsValid(why) || !detection_segment.IsValid(why) || !association.IsValid(why) ||
      !objects.IsValid(why) || !occupancy.IsValid(why) || !inventory.IsValid(why) ||
      !changes.IsValid(why) || !reassociation.IsValid(why) || !regeneration.IsValid(why) ||
      !views.IsValid(why)) {
    return false;
  }
  if (!(min_detection_score >= 0.f && min_detection_score <= 1.f)) {
    *why = "MapperConfig.min_detection_score must be in [0, 1]";
    return false;
  }
  if (min_segment_points < 1) {
    *why = "MapperConfig.min_segment_points must be >= 1";
    return false;
  }
  if (!(split_max_box_iou >= 0.f && split_max_box_iou <= 1.f)) {
    *why = "MapperConfig.split_max_box_iou must be in [0, 1]";
    return false;
  }
  if (!(min_stack_layer_gap_m > 0.f && min_stack_layer_gap_m < 1.f)) {
    *why = "MapperConfig.min_stack_layer_gap_m must be in (0, 1) m";
    return false;
  }
  if (!(flat_box_shrink_fraction >= 0.f && flat_box_shrink_fraction < 0.5f)) {
    *why = "MapperConfig.flat_box_shrink_fraction must be in [0, 0.5)";
    return false;
  }
  if (!(min_segment_box_fill >= 0.f && min_segment_box_fill <= 1.f)) {
    *why = "MapperConfig.min_segment_box_fill must be in [0, 1]";
    return false;
  }
  if (!(part_inside_fraction > 0.f && part_inside_fraction <= 1.f)) {
    *why = "MapperConfig.part_inside_fraction must be in (0, 1]";
    return false;
  }
  if (!(min_whole_to_part_area >= 1.f)) {
    *why = "MapperConfig.min_whole_to_part_area must be >= 1";
    return false;
  }
  return true;
}

}  // namespace objmap
