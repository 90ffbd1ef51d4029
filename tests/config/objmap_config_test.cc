// objmap's configuration file: the one objmap map, objmap_server and objmap_node read.
#include "config/objmap_config.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include "types/coco_classes.h"

namespace objmap {
namespace {

// Parses `yaml` over the defaults; the reason on failure.
std::string ParseError(const std::string& yaml) {
  ObjmapConfig config;
  std::string why;
  EXPECT_FALSE(ParseObjmapConfig(yaml, &config, &why)) << yaml;
  return why;
}

TEST(ObjmapConfig, ExampleFileHoldsExactlyTheDefaults) {
  ObjmapConfig loaded;
  std::string why;
  ASSERT_TRUE(LoadObjmapConfig(OBJMAP_EXAMPLE_CONFIG, &loaded, &why)) << why;
  // Every key of every section, compared through the one writer that lists them all.
  EXPECT_EQ(ObjmapConfigToYaml(loaded), ObjmapConfigToYaml(ObjmapConfig{}));
}

TEST(ObjmapConfig, KeysReplaceOnlyWhatTheySet) {
  ObjmapConfig config;
  std::string why;
  ASSERT_TRUE(ParseObjmapConfig(
      "occupancy: {resolution_m: 0.02, max_range_m: 3.5, one_ray_per_end_voxel: true}\n"
      "association:\n  match_distance_m: 0.03\n"
      "inventory: {min_observations: 5}\n"
      "objects: {model_voxel_size_m: 0.01}\n"
      "server: {max_queue: 8}\n"
      "store: {color_jpeg_quality: 75, synchronous: FULL}\n"
      "mapper: {surface_classes: [bed, 60], flat_classes: []}\n"
      "keyframes: {min_translation_m: 0.25, every_nth_frame: 3}\n"
      "detector: {score_threshold: 0.3}\n",
      &config, &why))
      << why;
  const MapperConfig& mapper = config.map_server.mapper;
  EXPECT_DOUBLE_EQ(mapper.occupancy.resolution_m, 0.02);
  EXPECT_DOUBLE_EQ(mapper.occupancy.max_range_m, 3.5);
  EXPECT_TRUE(mapper.occupancy.one_ray_per_end_voxel);
  EXPECT_DOUBLE_EQ(mapper.occupancy.probability_hit, OccupancyConfig{}.probability_hit);
  EXPECT_FLOAT_EQ(mapper.association.match_distance_m, 0.03f);
  EXPECT_EQ(mapper.inventory.min_observations, 5);
  EXPECT_FLOAT_EQ(mapper.objects.model_voxel_size_m, 0.01f);
  EXPECT_EQ(config.map_server.max_queue, 8);
  EXPECT_EQ(config.map_server.store.color_jpeg_quality, 75);
  EXPECT_EQ(config.map_server.store.synchronous, "FULL");
  EXPECT_EQ(mapper.surface_classes, (std::vector<int>{CocoClassId("bed"), 60}));
  EXPECT_TRUE(mapper.flat_classes.empty());
  EXPECT_FLOAT_EQ(config.detector.score_threshold, 0.3f);
  EXPECT_DOUBLE_EQ(config.keyframes.min_translation_m, 0.25);
  EXPECT_EQ(config.keyframes.every_nth_frame, 3);
  EXPECT_DOUBLE_EQ(config.keyframes.min_rotation_deg, KeyframeSelectorConfig{}.min_rotation_deg);
  EXPECT_TRUE(config.IsValid(&why)) << why;

  // The writer's output reads back to the same configuration.
  ObjmapConfig again;
  ASSERT_TRUE(ParseObjmapConfig(ObjmapConfigToYaml(config), &again, &why)) << why;
  EXPECT_EQ(ObjmapConfigToYaml(again), ObjmapConfigToYaml(config));
}

TEST(ObjmapConfig, EmptyTextKeepsTheDefaults) {
  ObjmapConfig config;
  std::string why;
  ASSERT_TRUE(ParseObjmapConfig("", &config, &why)) << why;
  ASSERT_TRUE(ParseObjmapConfig("# nothing\noccupancy:\n", &config, &why)) << why;
  EXPECT_EQ(ObjmapConfigToYaml(config), ObjmapConfigToYaml(ObjmapConfig{}));
}

TEST(ObjmapConfig, ErrorsNameTheKey) {
  EXPECT_EQ(
      ParseError("occupancy: {resolution: 0.02}").rfind("occupancy.resolution: unknown key", 0),
      0u);
  EXPECT_EQ(ParseError("occupancy: {resolution_m: fine}"),
            "occupancy.resolution_m: expected a number, got 'fine'");
  EXPECT_EQ(ParseError("server: {max_queue: 2.5}"),
            "server.max_queue: expected an integer, got '2.5'");
  EXPECT_EQ(ParseError("occupancy: {one_ray_per_end_voxel: maybe}"),
            "occupancy.one_ray_per_end_voxel: expected true or false, got 'maybe'");
  EXPECT_EQ(ParseError("mapper: {surface_classes: [bed, unicorn]}"),
            "mapper.surface_classes[1]: 'unicorn' is not a COCO class");
  EXPECT_EQ(ParseError("server: {max_queue: 1, max_queue: 2}"), "server.max_queue: appears twice");
  EXPECT_EQ(ParseError("occupancy: 3"), "occupancy: expected a mapping of keys, got '3'");
  EXPECT_EQ(ParseError("ocupancy: {}").rfind("unknown section 'ocupancy'", 0), 0u);
  EXPECT_NE(ParseError("occupancy: {resolution_m: [1").find("line"), std::string::npos);
}

TEST(ObjmapConfig, LoadChecksValuesAndNamesTheFile) {
  const std::string path =
      ::testing::TempDir() + "objmap_config_" + std::to_string(getpid()) + "_invalid.yaml";
  std::ofstream(path) << "store: {color_jpeg_quality: 0}\n";
  ObjmapConfig config;
  std::string why;
  EXPECT_FALSE(LoadObjmapConfig(path, &config, &why));
  EXPECT_EQ(why.rfind(path + ": ", 0), 0u) << why;
  EXPECT_NE(why.find("color_jpeg_quality"), std::string::npos) << why;
  std::remove(path.c_str());
  EXPECT_FALSE(LoadObjmapConfig(path, &config, &why));
  EXPECT_NE(why.find("cannot open"), std::string::npos) << why;
}

TEST(ObjmapConfig, EmptyModelPathMeansTheInstalledModel) {
  ObjmapConfig config;
  EXPECT_TRUE(config.detector.model_path.empty());
  std::string why;
  EXPECT_TRUE(config.IsValid(&why)) << why;
  config.keyframes.every_nth_frame = -1;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_EQ(why.rfind("keyframes: ", 0), 0u) << why;
}

TEST(ObjmapConfig, SessionKeysParseAndAreChecked) {
  ObjmapConfig config;
  std::string why;
  ASSERT_TRUE(SetObjmapConfigKey("server.pose_source=session_frame", &config, &why)) << why;
  ASSERT_TRUE(SetObjmapConfigKey("server.relocalisation_map_keyframes=500", &config, &why)) << why;
  ASSERT_TRUE(SetObjmapConfigKey("inventory.absent_min_visibility=0.7", &config, &why)) << why;
  EXPECT_EQ(config.map_server.pose_source, PoseSource::kSessionFrame);
  EXPECT_EQ(config.map_server.relocalisation_map_keyframes, 500);
  EXPECT_FLOAT_EQ(config.map_server.mapper.inventory.absent_min_visibility, 0.7f);
  EXPECT_TRUE(config.IsValid(&why)) << why;
  EXPECT_NE(ObjmapConfigToYaml(config).find("pose_source: session_frame"), std::string::npos);

  EXPECT_FALSE(SetObjmapConfigKey("server.pose_source=gps", &config, &why));
  EXPECT_NE(why.find("expected request, estimate or session_frame, got"), std::string::npos)
      << why;
  config.map_server.relocalisation_map_keyframes = -1;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("relocalisation_map_keyframes"), std::string::npos) << why;
}

TEST(ObjmapConfig, SetKeyGoesThroughTheFileReader) {
  ObjmapConfig config;
  std::string why;
  ASSERT_TRUE(SetObjmapConfigKey("occupancy.resolution_m=0.02", &config, &why)) << why;
  ASSERT_TRUE(SetObjmapConfigKey("mapper.flat_classes=[tv, keyboard]", &config, &why)) << why;
  ASSERT_TRUE(SetObjmapConfigKey("store.synchronous=FULL", &config, &why)) << why;
  ASSERT_TRUE(SetObjmapConfigKey("detector.model_path=/opt/m.pb", &config, &why)) << why;
  ASSERT_TRUE(SetObjmapConfigKey("occupancy.one_ray_per_end_voxel=true", &config, &why)) << why;
  EXPECT_DOUBLE_EQ(config.map_server.mapper.occupancy.resolution_m, 0.02);
  EXPECT_EQ(config.map_server.mapper.flat_classes,
            (std::vector<int>{CocoClassId("tv"), CocoClassId("keyboard")}));
  EXPECT_EQ(config.map_server.store.synchronous, "FULL");
  EXPECT_EQ(config.detector.model_path, "/opt/m.pb");
  EXPECT_TRUE(config.map_server.mapper.occupancy.one_ray_per_end_voxel);
  // Only the key set changed.
  ObjmapConfig expected;
  expected.map_server.mapper.occupancy.resolution_m = 0.02;
  expected.map_server.mapper.flat_classes = {CocoClassId("tv"), CocoClassId("keyboard")};
  expected.map_server.store.synchronous = "FULL";
  expected.detector.model_path = "/opt/m.pb";
  expected.map_server.mapper.occupancy.one_ray_per_end_voxel = true;
  EXPECT_EQ(ObjmapConfigToYaml(config), ObjmapConfigToYaml(expected));

  EXPECT_FALSE(SetObjmapConfigKey("occupancy.resolution=0.02", &config, &why));
  EXPECT_EQ(why.rfind("occupancy.resolution: unknown key", 0), 0u) << why;
  EXPECT_FALSE(SetObjmapConfigKey("occupancy.resolution_m=fine", &config, &why));
  EXPECT_EQ(why, "occupancy.resolution_m: expected a number, got 'fine'");
  EXPECT_FALSE(SetObjmapConfigKey("ocupancy.resolution_m=0.02", &config, &why));
  EXPECT_EQ(why.rfind("unknown section 'ocupancy'", 0), 0u) << why;
  for (const char* malformed : {"resolution_m=0.02", "occupancy.resolution_m", ".x=1", "a.=1"}) {
    EXPECT_FALSE(SetObjmapConfigKey(malformed, &config, &why)) << malformed;
    EXPECT_NE(why.find("section.key=value"), std::string::npos) << why;
  }
  EXPECT_DOUBLE_EQ(config.map_server.mapper.occupancy.resolution_m, 0.02);
}

}  // namespace
}  // namespace objmap
