// objmap_server's YAML configuration and command line.
#include "server_config.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include "server_options.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// Parses `yaml` over the defaults; the reason on failure.
std::string ParseError(const std::string& yaml) {
  ServerConfig config;
  std::string why;
  EXPECT_FALSE(ParseServerConfig(yaml, &config, &why)) << yaml;
  return why;
}

TEST(ServerConfig, ExampleFileHoldsExactlyTheDefaults) {
  ServerConfig loaded;
  std::string why;
  ASSERT_TRUE(LoadServerConfig(OBJMAP_EXAMPLE_CONFIG, &loaded, &why)) << why;
  // Every key of every section, compared through the one writer that lists them all.
  EXPECT_EQ(ServerConfigToYaml(loaded), ServerConfigToYaml(ServerConfig{}));
}

TEST(ServerConfig, KeysReplaceOnlyWhatTheySet) {
  ServerConfig config;
  std::string why;
  ASSERT_TRUE(ParseServerConfig(
      "occupancy: {resolution_m: 0.02, max_range_m: 3.5, one_ray_per_end_voxel: true}\n"
      "association:\n  match_distance_m: 0.03\n"
      "inventory: {min_observations: 5}\n"
      "objects: {model_voxel_size_m: 0.01}\n"
      "server: {max_queue: 8}\n"
      "store: {color_jpeg_quality: 75, synchronous: FULL}\n"
      "mapper: {surface_classes: [bed, 60], flat_classes: []}\n"
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
  EXPECT_TRUE(config.IsValid(&why)) << why;

  // The writer's output reads back to the same configuration.
  ServerConfig again;
  ASSERT_TRUE(ParseServerConfig(ServerConfigToYaml(config), &again, &why)) << why;
  EXPECT_EQ(ServerConfigToYaml(again), ServerConfigToYaml(config));
}

TEST(ServerConfig, EmptyTextKeepsTheDefaults) {
  ServerConfig config;
  std::string why;
  ASSERT_TRUE(ParseServerConfig("", &config, &why)) << why;
  ASSERT_TRUE(ParseServerConfig("# nothing\noccupancy:\n", &config, &why)) << why;
  EXPECT_EQ(ServerConfigToYaml(config), ServerConfigToYaml(ServerConfig{}));
}

TEST(ServerConfig, ErrorsNameTheKey) {
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

TEST(ServerConfig, LoadChecksValuesAndNamesTheFile) {
  const std::string path =
      ::testing::TempDir() + "objmap_server_config_" + std::to_string(getpid()) + "_invalid.yaml";
  std::ofstream(path) << "store: {color_jpeg_quality: 0}\n";
  ServerConfig config;
  std::string why;
  EXPECT_FALSE(LoadServerConfig(path, &config, &why));
  EXPECT_EQ(why.rfind(path + ": ", 0), 0u) << why;
  EXPECT_NE(why.find("color_jpeg_quality"), std::string::npos) << why;
  std::remove(path.c_str());
  EXPECT_FALSE(LoadServerConfig(path, &config, &why));
  EXPECT_NE(why.find("cannot open"), std::string::npos) << why;
}

TEST(ServerOptions, ParsesFlagsWithSpacesOrEquals) {
  const char* argv[] = {"objmap_server",
                        "--db",
                        "map.db",
                        "--listen=127.0.0.1:0",
                        "--no-detector",
                        "--max-message-mb",
                        "16",
                        "--config",
                        "c.yaml"};
  ServerOptions options;
  std::string why;
  ASSERT_TRUE(ParseServerOptions(9, argv, &options, &why)) << why;
  EXPECT_EQ(options.db_path, "map.db");
  EXPECT_EQ(options.grpc.listen_address, "127.0.0.1:0");
  EXPECT_TRUE(options.no_detector);
  EXPECT_EQ(options.grpc.max_receive_message_mb, 16);
  EXPECT_EQ(options.config_path, "c.yaml");
  EXPECT_TRUE(options.model_path.empty());
}

TEST(ServerOptions, DefaultsToLoopbackAndRejectsBadCommandLines) {
  const char* ok[] = {"objmap_server", "--db", "map.db"};
  ServerOptions options;
  std::string why;
  ASSERT_TRUE(ParseServerOptions(3, ok, &options, &why)) << why;
  EXPECT_EQ(options.grpc.listen_address, "127.0.0.1:50051");
  EXPECT_EQ(options.grpc.max_receive_message_mb, 64);

  const char* no_db[] = {"objmap_server", "--listen", "127.0.0.1:1"};
  options = ServerOptions{};
  EXPECT_FALSE(ParseServerOptions(3, no_db, &options, &why));
  EXPECT_NE(why.find("--db"), std::string::npos) << why;
  const char* missing_value[] = {"objmap_server", "--db", "--no-detector"};
  EXPECT_FALSE(ParseServerOptions(3, missing_value, &options, &why));
  EXPECT_EQ(why, "--db needs a value");
  const char* unknown[] = {"objmap_server", "--db", "m.db", "--port", "1"};
  EXPECT_FALSE(ParseServerOptions(5, unknown, &options, &why));
  EXPECT_EQ(why, "unknown option --port");
  const char* bad_size[] = {"objmap_server", "--db", "m.db", "--max-message-mb", "lots"};
  EXPECT_FALSE(ParseServerOptions(5, bad_size, &options, &why));
  EXPECT_NE(why.find("--max-message-mb"), std::string::npos) << why;
  // Out-of-range values are refused with the command line, before the database is opened.
  const char* too_big[] = {"objmap_server", "--db", "m.db", "--max-message-mb", "4096"};
  EXPECT_FALSE(ParseServerOptions(5, too_big, &options, &why));
  EXPECT_EQ(why, "--max-message-mb: max message size 4096 MiB must lie in 1..2047");
  const char* no_port[] = {"objmap_server", "--db", "m.db", "--listen", "localhost"};
  EXPECT_FALSE(ParseServerOptions(5, no_port, &options, &why));
  EXPECT_EQ(why, "--listen: listen address 'localhost' must be host:port");
}

}  // namespace
}  // namespace objmap
