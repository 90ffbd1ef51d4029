// objmap_server's command line.
#include "server_options.h"

#include <gtest/gtest.h>

namespace objmap {
namespace {

TEST(ServerOptions, ParsesFlagsWithSpacesOrEquals) {
  const char* argv[] = {"objmap_server",
                        "--db",
                        "map.db",
                        "--listen=127.0.0.1:0",
                        "--no-detector",
                        "--max-message-mb",
                        "16",
                        "--config",
                        "c.yaml",
                        "--set",
                        "occupancy.resolution_m=0.02",
                        "--set=inventory.min_observations=2"};
  ServerOptions options;
  std::string why;
  ASSERT_TRUE(ParseServerOptions(12, argv, &options, &why)) << why;
  EXPECT_EQ(options.config_keys, (std::vector<std::string>{"occupancy.resolution_m=0.02",
                                                           "inventory.min_observations=2"}));
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
