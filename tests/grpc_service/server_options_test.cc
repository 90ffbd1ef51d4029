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

// Serving other machines without TLS and tokens is refused unless asked for with --insecure.
TEST(ServerOptions, AnAddressOtherMachinesReachNeedsTlsAndTokensOrInsecure) {
  for (const char* loopback : {"127.0.0.1:0", "127.1.2.3:50051", "localhost:1", "[::1]:1"}) {
    EXPECT_TRUE(grpc_service::IsLoopbackAddress(loopback)) << loopback;
  }
  for (const char* exposed : {"0.0.0.0:50051", "[::]:50051", "192.168.1.20:1", "robot:50051"}) {
    EXPECT_FALSE(grpc_service::IsLoopbackAddress(exposed)) << exposed;
  }
  std::string why;
  ServerOptions options;
  const char* exposed[] = {"objmap_server", "--db", "m.db", "--listen", "0.0.0.0:50051"};
  EXPECT_FALSE(ParseServerOptions(5, exposed, &options, &why));
  EXPECT_EQ(why,
            "--listen: listen address 0.0.0.0:50051 reaches other machines: serve it with TLS and "
            "tokens (--tls-cert, --tls-key, --tokens), or give --insecure to serve it without");

  options = ServerOptions{};
  const char* insecure[] = {"objmap_server", "--db", "m.db", "--listen", "0.0.0.0:50051",
                            "--insecure"};
  ASSERT_TRUE(ParseServerOptions(6, insecure, &options, &why)) << why;
  EXPECT_TRUE(options.grpc.insecure);
  EXPECT_TRUE(options.grpc.ExposedWithoutProtection());

  options = ServerOptions{};
  const char* protected_[] = {"objmap_server", "--db",      "m.db",     "--listen",
                              "0.0.0.0:50051", "--tls-cert", "s.pem",   "--tls-key",
                              "s.key",         "--tokens",   "t.txt",   "--tls-client-ca",
                              "ca.pem"};
  ASSERT_TRUE(ParseServerOptions(13, protected_, &options, &why)) << why;
  EXPECT_FALSE(options.grpc.ExposedWithoutProtection());
  EXPECT_EQ(options.grpc.tls_client_ca_path, "ca.pem");
  EXPECT_EQ(options.grpc.tokens_path, "t.txt");

  options = ServerOptions{};
  const char* cert_only[] = {"objmap_server", "--db", "m.db", "--tls-cert", "s.pem"};
  EXPECT_FALSE(ParseServerOptions(5, cert_only, &options, &why));
  EXPECT_EQ(why, "TLS needs both a certificate and its key (--tls-cert and --tls-key)");
  options = ServerOptions{};
  const char* ca_only[] = {"objmap_server", "--db", "m.db", "--tls-client-ca", "ca.pem"};
  EXPECT_FALSE(ParseServerOptions(5, ca_only, &options, &why));
  EXPECT_EQ(why, "client certificates (--tls-client-ca) need TLS (--tls-cert and --tls-key)");
}

}  // namespace
TEST(ServerOptions, TheViewerIsOffByDefaultAndOnLoopbackUnlessInsecure) {
  const char* plain[] = {"objmap_server", "--db", "map.db"};
  ServerOptions options;
  std::string why;
  ASSERT_TRUE(ParseServerOptions(3, plain, &options, &why)) << why;
  EXPECT_TRUE(options.http_address.empty());

  const char* port_only[] = {"objmap_server", "--db", "map.db", "--http", "8480",
                             "--viewer-dir=web"};
  options = ServerOptions();
  ASSERT_TRUE(ParseServerOptions(6, port_only, &options, &why)) << why;
  EXPECT_EQ(options.http_address, "8480");
  EXPECT_EQ(options.viewer_folder, "web");

  const char* bad_port[] = {"objmap_server", "--db", "map.db", "--http", "127.0.0.1:web"};
  options = ServerOptions();
  EXPECT_FALSE(ParseServerOptions(5, bad_port, &options, &why));
  EXPECT_NE(why.find("--http"), std::string::npos) << why;

  const char* exposed[] = {"objmap_server", "--db", "map.db", "--http", "0.0.0.0:8480"};
  options = ServerOptions();
  EXPECT_FALSE(ParseServerOptions(5, exposed, &options, &why));
  EXPECT_NE(why.find("--insecure"), std::string::npos) << why;

  const char* told[] = {"objmap_server", "--db", "map.db", "--http", "0.0.0.0:8480",
                        "--listen", "0.0.0.0:50051", "--insecure"};
  options = ServerOptions();
  EXPECT_TRUE(ParseServerOptions(8, told, &options, &why)) << why;
}

}  // namespace objmap
