#pragma once
// The list of sections and keys of objmap's configuration file, walked by its YAML reader and
// writer (objmap_config.cc) and by objmap_node's ROS-parameter reader
// (server/ros_node/node_config.cc).

#include "config/objmap_config.h"

namespace objmap::internal {

// Every section and key of the file, in the example's order. Reading and writing both walk this
// one list, so the two cannot disagree about a key's name.
template <typename Visitor>
void VisitMapper(MapperConfig* m, Visitor& v) {
  v.Section("mapper");
  v("min_detection_score", &m->min_detection_score);
  v("min_segment_points", &m->min_segment_points);
  v("surface_classes", &m->surface_classes);
  v("flat_classes", &m->flat_classes);
  v("flat_box_shrink_fraction", &m->flat_box_shrink_fraction);
  v("split_max_box_iou", &m->split_max_box_iou);
  v("stack_classes", &m->stack_classes);
  v("min_stack_layer_gap_m", &m->min_stack_layer_gap_m);
  v("min_segment_box_fill", &m->min_segment_box_fill);
  v("part_classes", &m->part_classes);
  v("whole_classes", &m->whole_classes);
  v("part_inside_fraction", &m->part_inside_fraction);
  v("min_whole_to_part_area", &m->min_whole_to_part_area);
  v("occupancy_second_copy", &m->occupancy_second_copy);
  SegmenterConfig& s = m->segmenter;
  v.Section("segmenter");
  v("depth_jump_ratio", &s.depth_jump_ratio);
  v("normal_step_px", &s.normal_step_px);
  v("max_planes", &s.max_planes);
  v("min_plane_area_m2", &s.min_plane_area_m2);
  v("min_plane_patch_area_m2", &s.min_plane_patch_area_m2);
  v("plane_distance_m", &s.plane_distance_m);
  v("plane_normal_angle_deg", &s.plane_normal_angle_deg);
  v("plane_iterations", &s.plane_iterations);
  v("cell_px", &s.cell_px);
  v("kruskal_k_px", &s.kruskal_k_px);
  v("convex_tolerance", &s.convex_tolerance);
  v("min_segment_px", &s.min_segment_px);
  DetectionSegmentConfig& d = m->detection_segment;
  v.Section("detection_segment");
  v("dilation_px", &d.dilation_px);
  v("dilation_fraction", &d.dilation_fraction);
  v("min_inside_fraction", &d.min_inside_fraction);
  v("max_box_area_ratio", &d.max_box_area_ratio);
  v("min_segment_px", &d.min_segment_px);
  v("depth_gate_m", &d.depth_gate_m);
  v("min_iou_gain", &d.min_iou_gain);
  v("fallback_inside_fraction", &d.fallback_inside_fraction);
}

template <typename Visitor>
void VisitMapModel(MapperConfig* m, Visitor& v) {
  AssociationConfig& a = m->association;
  v.Section("association");
  v("candidate_margin_m", &a.candidate_margin_m);
  v("match_distance_m", &a.match_distance_m);
  v("duplicate_distance_m", &a.duplicate_distance_m);
  v("min_match_fraction", &a.min_match_fraction);
  v("max_test_points", &a.max_test_points);
  v("min_class_share", &a.min_class_share);
  v.Section("objects");
  v("model_voxel_size_m", &m->objects.model_voxel_size_m);
  v("min_voxel_observations", &m->objects.min_voxel_observations);
  v("resolve_shared_voxels", &m->objects.resolve_shared_voxels);
  v("thin_classes", &m->objects.thin_classes);
  v("max_thin_thickness_m", &m->objects.max_thin_thickness_m);
  OccupancyConfig& o = m->occupancy;
  v.Section("occupancy");
  v("resolution_m", &o.resolution_m);
  v("max_range_m", &o.max_range_m);
  v("probability_hit", &o.probability_hit);
  v("probability_miss", &o.probability_miss);
  v("clamping_min", &o.clamping_min);
  v("clamping_max", &o.clamping_max);
  v("object_margin_voxels", &o.object_margin_voxels);
  v("structure_margin_m", &o.structure_margin_m);
  v("structure_margin_per_m2", &o.structure_margin_per_m2);
  v("one_ray_per_end_voxel", &o.one_ray_per_end_voxel);
  v("threads_per_scan", &o.threads_per_scan);
  InventoryConfig& i = m->inventory;
  v.Section("inventory");
  v("min_evidence", &i.min_evidence);
  v("miss_weight", &i.miss_weight);
  v("min_confidence", &i.min_confidence);
  v("min_observations", &i.min_observations);
  v("detectable_area_px", &i.detectable_area_px);
  v("absent_min_visibility", &i.absent_min_visibility);
  v("occlusion_margin_m", &i.occlusion_margin_m);
  v("occlusion_margin_per_m2", &i.occlusion_margin_per_m2);
  v("max_visibility_points", &i.max_visibility_points);
  v("unknown_view_score", &i.unknown_view_score);
  v("unknown_min_views", &i.unknown_min_views);
  v("count_unknown", &i.count_unknown);
  ChangeConfig& c = m->changes;
  v.Section("changes");
  v("enabled", &c.enabled);
  v("see_through_margin_m", &c.see_through_margin_m);
  v("see_through_margin_per_m2", &c.see_through_margin_per_m2);
  v("min_visible_fraction", &c.min_visible_fraction);
  v("min_projected_area_px", &c.min_projected_area_px);
  v("min_empty_fraction", &c.min_empty_fraction);
  v("min_empty_fraction_over_present", &c.min_empty_fraction_over_present);
  v("min_empty_views", &c.min_empty_views);
  v("max_move_size_ratio", &c.max_move_size_ratio);
  v("min_move_distance_m", &c.min_move_distance_m);
  v("min_move_colour_overlap", &c.min_move_colour_overlap);
  v("move_ambiguity_overlap_margin", &c.move_ambiguity_overlap_margin);
  UnknownObjectConfig& u = m->unknown_objects;
  v.Section("unknown_objects");
  v("enabled", &u.enabled);
  v("min_segment_px", &u.min_segment_px);
  v("image_border_px", &u.image_border_px);
  v("max_claimed_fraction", &u.max_claimed_fraction);
  v("max_support_gap_m", &u.max_support_gap_m);
  v("min_height_m", &u.min_height_m);
  v("min_extent_m", &u.min_extent_m);
  v("max_extent_m", &u.max_extent_m);
  v.Section("views");
  v("translation_m", &m->views.translation_m);
  v("rotation_deg", &m->views.rotation_deg);
  ReassociationConfig& r = m->reassociation;
  v.Section("reassociation");
  v("enabled", &r.enabled);
  v("min_translation_m", &r.min_translation_m);
  v("min_rotation_rad", &r.min_rotation_rad);
  RegenerationConfig& g = m->regeneration;
  v.Section("regeneration");
  v("threads", &g.threads);
  v("incremental_max_moved_fraction", &g.incremental_max_moved_fraction);
}

template <typename Visitor>
void VisitObjmapConfig(ObjmapConfig* c, Visitor& v) {
  MapServerConfig& s = c->map_server;
  v.Section("server");
  v("max_queue", &s.max_queue);
  v("change_history", &s.change_history);
  v("max_query_volume_m3", &s.max_query_volume_m3);
  v("max_listed_voxels", &s.max_listed_voxels);
  v("checkpoint_every_keyframes", &s.checkpoint_every_keyframes);
  v("checkpoint_work_ratio", &s.checkpoint_work_ratio);
  v("pose_source", &s.pose_source);
  v("relocalisation_map_keyframes", &s.relocalisation_map_keyframes);
  v("max_held_keyframes", &s.max_held_keyframes);
  v("estimate_from_first_pose", &s.estimate_from_first_pose);
  // The request limits (RequestLimits) sit beside the server's other bounds.
  v("max_image_pixels", &s.limits.max_image_pixels);
  v("max_detections_per_keyframe", &s.limits.max_detections_per_keyframe);
  v("max_poses_per_update", &s.limits.max_poses_per_update);
  v("max_string_bytes", &s.limits.max_string_bytes);
  v("heavy_query_threads", &s.fairness.heavy_query_threads);
  v("heavy_query_nice", &s.fairness.heavy_query_nice);
  v("max_waiting_heavy_queries", &s.fairness.max_waiting_heavy_queries);
  v.Section("store");
  v("color_jpeg_quality", &s.store.color_jpeg_quality);
  v("busy_timeout_ms", &s.store.busy_timeout_ms);
  v("synchronous", &s.store.synchronous);
  RevisitThinningConfig& t = s.thinning;
  v.Section("thinning");
  v("enabled", &t.enabled);
  v("max_distance_m", &t.max_distance_m);
  v("max_angle_deg", &t.max_angle_deg);
  v("max_views", &t.max_views);
  v("pixel_stride", &t.pixel_stride);
  v("depth_margin_m", &t.depth_margin_m);
  v("depth_margin_per_m2", &t.depth_margin_per_m2);
  v("min_explained_fraction", &t.min_explained_fraction);
  v("max_changed_patch_px", &t.max_changed_patch_px);
  v("min_depth_fraction", &t.min_depth_fraction);
  v("min_partial_explained_fraction", &t.min_partial_explained_fraction);
  v("min_new_fraction_in_box", &t.min_new_fraction_in_box);
  v("box_margin", &t.box_margin);
  VisitMapper(&s.mapper, v);
  VisitMapModel(&s.mapper, v);
  KeyframeSelectorConfig& k = c->keyframes;
  v.Section("keyframes");
  v("min_translation_m", &k.min_translation_m);
  v("min_rotation_deg", &k.min_rotation_deg);
  v("every_nth_frame", &k.every_nth_frame);
  CenterNetConfig& d = c->detector;
  v.Section("detector");
  v("model_path", &d.model_path);
  v("score_threshold", &d.score_threshold);
  v("input_size", &d.input_size);
  v("max_detections", &d.max_detections);
  v("num_threads", &d.num_threads);
  v("nms_iou", &d.nms_iou);
  v("tiles_per_side", &d.tiles_per_side);
  v("tile_overlap", &d.tile_overlap);
  v.Finish();
}

}  // namespace objmap::internal
