// The real objmap_server killed and restarted: `objmap ingest --resume` goes on after a run cut
// short, and a kill -9 soak finds every acknowledged keyframe and an intact database after each
// restart.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "cli/run_objmap.h"
#include "dataset/sequence_reader.h"
#include "integration/server_process.h"
#include "objmap/client.h"
#include "objmap/keyframe_request.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> KeyframeNames(const std::string& address) {
  MapClient client(address);
  v1::ListKeyframesResponse listed;
  const grpc::Status status = client.ListKeyframes(v1::ListKeyframesRequest(), &listed);
  EXPECT_TRUE(status.ok()) << status.error_message();
  std::vector<std::string> names;
  for (const v1::KeyframeInfo& keyframe : listed.keyframes()) names.push_back(keyframe.name());
  return names;
}

// Renders a small desk sequence into `dir`/desk with objmap_sim; returns its folder.
std::string RenderDesk(const fs::path& dir, int frames) {
  const std::string scene = (dir / "desk").string();
  const testing::CommandResult rendered =
      testing::RunCommand(std::string(OBJMAP_SIM_PATH) + " --out " + scene +
                          " --kind desk --seed 5 --frames " + std::to_string(frames));
  EXPECT_EQ(rendered.exit_code, 0) << rendered.output;
  return scene;
}

// Runs a query on the database file as another program would; the rows' first column.
std::vector<std::string> Query(const std::string& db_path, const std::string& sql) {
  sqlite3* db = nullptr;
  std::vector<std::string> rows;
  if (sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << "cannot open " << db_path;
    sqlite3_close(db);
    return rows;
  }
  sqlite3_stmt* statement = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr), SQLITE_OK)
      << sqlite3_errmsg(db);
  while (statement != nullptr && sqlite3_step(statement) == SQLITE_ROW) {
    const unsigned char* text = sqlite3_column_text(statement, 0);
    rows.emplace_back(text != nullptr ? reinterpret_cast<const char*>(text) : "");
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return rows;
}

// kill -9 at random moments of an ingest, each into a named session of its own, ten times: after
// each restart every acknowledged keyframe is stored (and nothing twice) in the session it was
// acknowledged in, as a keyframe or, where it repeated a stored view of an earlier round (the
// rounds send the same frames), as a revisit; every such session is stored with its name, and
// SQLite's integrity check passes.
TEST(KillSoak, EveryAcknowledgedKeyframeSurvivesTenKills) {
  const fs::path dir = fs::temp_directory_path() / ("objmap_soak_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string why;
  const std::unique_ptr<SequenceReader> reader = OpenSequence(RenderDesk(dir, 40), &why);
  ASSERT_TRUE(reader) << why;
  std::vector<v1::AddKeyframeRequest> frames;
  for (std::size_t i = 0; i < reader->size(); i += 2) {
    RgbdFrame frame;
    ASSERT_TRUE(reader->ReadFrame(i, &frame, &why)) << why;
    frames.emplace_back();
    ASSERT_TRUE(MakeAddKeyframeRequest(frame, nullptr, KeyframeEncoding{}, &frames.back(), &why))
        << why;
  }
  const std::string db = (dir / "soak.db").string(), log = (dir / "soak.log").string();
  std::mt19937 random(2026);
  std::set<std::string> acknowledged;
  std::map<std::string, std::int64_t> session_of;  // acknowledged keyframe -> its session
  std::map<std::int64_t, std::string> session_names;  // sessions started, by id
  std::set<std::string> revisits_acknowledged;        // acknowledged as revisits of stored views
  int rounds_with_acknowledgements = 0;
  for (int round = 0; round < 10; ++round) {
    testing::ServerProcess server(OBJMAP_SERVER_PATH, db, log, {"--no-detector"});
    ASSERT_TRUE(server.Start(std::chrono::seconds(60), &why)) << why;
    MapClient client(server.address());
    std::mutex mutex;
    int acknowledged_this_round = 0;
    // A named session, then writes until the server dies; the kill lands at a random moment of
    // one of them (or of the session's start).
    std::thread writer([&] {
      v1::StartSessionRequest start;
      start.set_name("round " + std::to_string(round));
      v1::Session session;
      if (!client.StartSession(start, &session).ok()) return;
      {
        std::lock_guard<std::mutex> lock(mutex);
        session_names[session.id()] = session.name();
      }
      for (std::size_t k = 0;; ++k) {
        v1::AddKeyframeRequest request = frames[k % frames.size()];
        request.set_name("round-" + std::to_string(round) + "-" + std::to_string(k));
        v1::AddKeyframeResponse response;
        if (!client.AddKeyframe(request, &response).ok()) return;
        std::lock_guard<std::mutex> lock(mutex);
        acknowledged.insert(request.name());
        session_of[request.name()] = response.session_id();
        // keyframe_id 0: kept as a revisit only (a keyframe that repeated the stored views in
        // part is stored as a keyframe, with a revisit row too).
        if (response.keyframe_id() == 0) revisits_acknowledged.insert(request.name());
        ++acknowledged_this_round;
      }
    });
    std::this_thread::sleep_for(
        std::chrono::milliseconds(std::uniform_int_distribution<int>(100, 900)(random)));
    EXPECT_EQ(server.Kill(SIGKILL), 128 + SIGKILL);
    writer.join();
    if (acknowledged_this_round > 0) ++rounds_with_acknowledgements;

    EXPECT_EQ(Query(db, "PRAGMA integrity_check"), std::vector<std::string>{"ok"}) << round;
    const std::vector<std::string> names = Query(db, "SELECT name FROM keyframes");
    const std::set<std::string> stored(names.begin(), names.end());
    EXPECT_EQ(stored.size(), names.size()) << "a keyframe stored twice, round " << round;
    const std::vector<std::string> revisit_names = Query(db, "SELECT name FROM revisits");
    const std::set<std::string> stored_revisits(revisit_names.begin(), revisit_names.end());
    EXPECT_EQ(stored_revisits.size(), revisit_names.size())
        << "a revisit stored twice, round " << round;
    for (const std::string& name : acknowledged) {
      const bool revisit_only = revisits_acknowledged.count(name) > 0;
      EXPECT_EQ(stored.count(name), revisit_only ? 0u : 1u)
          << name << " was acknowledged and is lost, round " << round;
      if (revisit_only) {
        EXPECT_EQ(stored_revisits.count(name), 1u)
            << name << " was acknowledged as a revisit and is lost, round " << round;
      }
    }
    // Each acknowledged keyframe is stored in the session it was acknowledged in, and that
    // session with its name: no session is lost.
    const std::vector<std::string> keyframe_sessions =
        Query(db,
              "SELECT name || ' ' || session_id FROM keyframes UNION "
              "SELECT name || ' ' || session_id FROM revisits");
    const std::set<std::string> stored_pairs(keyframe_sessions.begin(), keyframe_sessions.end());
    for (const auto& [name, session_id] : session_of) {
      EXPECT_EQ(stored_pairs.count(name + " " + std::to_string(session_id)), 1u)
          << name << " is not stored in session " << session_id << ", round " << round;
      const std::vector<std::string> row =
          Query(db, "SELECT name FROM sessions WHERE id = " + std::to_string(session_id));
      EXPECT_EQ(row, std::vector<std::string>{session_names[session_id]})
          << "session " << session_id << ", round " << round;
    }
    EXPECT_EQ(Query(db, "SELECT count(*) FROM keyframes WHERE session_id NOT IN "
                        "(SELECT id FROM sessions)"),
              std::vector<std::string>{"0"})
        << "keyframes of a session without its row, round " << round;
    EXPECT_EQ(Query(db,
                    "SELECT count(*) FROM revisits WHERE session_id NOT IN "
                    "(SELECT id FROM sessions)"),
              std::vector<std::string>{"0"})
        << "revisits of a session without its row, round " << round;
  }
  EXPECT_GE(rounds_with_acknowledgements, 5) << "the kills came before any write was done";
  // The last restart serves the map of every stored keyframe.
  testing::ServerProcess server(OBJMAP_SERVER_PATH, db, log, {"--no-detector"});
  ASSERT_TRUE(server.Start(std::chrono::seconds(60), &why)) << why;
  v1::StatusResponse status;
  ASSERT_TRUE(MapClient(server.address()).Status(v1::StatusRequest(), &status).ok());
  EXPECT_EQ(status.keyframes(),
            static_cast<std::int64_t>(Query(db, "SELECT name FROM keyframes").size()));
  std::cout << acknowledged.size() << " keyframes acknowledged over 10 kills, "
            << status.keyframes() << " stored as keyframes, " << revisits_acknowledged.size()
            << " kept as revisits only" << std::endl;
  server.Kill(SIGTERM);
  fs::remove_all(dir);
}

TEST(IngestResume, ARunCutShortGoesOnWithoutDuplicates) {
  const fs::path dir = fs::temp_directory_path() / ("objmap_resume_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = RenderDesk(dir, 60);
  const std::string inputs = " " + scene + " --detections " + scene + "/detections.json";

  // The reference: one whole run into a fresh database.
  testing::ServerProcess whole(OBJMAP_SERVER_PATH, (dir / "whole.db").string(),
                               (dir / "whole.log").string(), {"--no-detector"});
  std::string why;
  ASSERT_TRUE(whole.Start(std::chrono::seconds(60), &why)) << why;
  testing::CommandResult run = testing::RunObjmap("ingest" + inputs + " --server " + whole.address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<std::string> expected = KeyframeNames(whole.address());
  ASSERT_GE(expected.size(), 5u);

  // A run cut short after 3 keyframes, a server killed and restarted on its file, a resume.
  const std::string db = (dir / "resumed.db").string(), log = (dir / "resumed.log").string();
  auto server = std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, db, log,
                                                         std::vector<std::string>{"--no-detector"});
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why;
  run = testing::RunObjmap("ingest" + inputs + " --max-keyframes 3 --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  server->Kill(SIGKILL);
  server = std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, db, log,
                                                    std::vector<std::string>{"--no-detector"});
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why << "\n" << server->Log();
  run = testing::RunObjmap("ingest" + inputs + " --resume --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("resuming: the server holds 3 keyframes"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find(std::to_string(expected.size() - 3) + " added of"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("3 already held"), std::string::npos) << run.output;
  EXPECT_EQ(KeyframeNames(server->address()), expected);
  server.reset();
  fs::remove_all(dir);
}

// Sessions through the real server and the CLI: a run, a kill -9, a restart and a named run:
// both runs are listed with their keyframes, the killed one without an end, and nothing is lost.
TEST(Sessions, ARunAKillARestartAndANamedRunAreListedByTheCliAndTheFile) {
  const fs::path dir =
      fs::temp_directory_path() / ("objmap_sessions_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = RenderDesk(dir, 40);
  const std::string inputs = " " + scene + " --detections " + scene + "/detections.json";
  const std::string db = (dir / "map.db").string(), log = (dir / "server.log").string();
  const std::vector<std::string> flags = {"--no-detector"};
  std::string why;

  auto server = std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, db, log, flags);
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why;
  testing::CommandResult run =
      testing::RunObjmap("ingest" + inputs + " --max-frames 20 --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::size_t first_run = KeyframeNames(server->address()).size();
  ASSERT_GE(first_run, 2u);
  server->Kill(SIGKILL);

  server = std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, db, log, flags);
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why << "\n" << server->Log();
  // The restart opened session 2; nothing was mapped in it, so the named run takes its id.
  run = testing::RunObjmap("ingest" + inputs + " --first-frame 20 --session 'second run' --server " +
                           server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("started session 2 \"second run\""), std::string::npos) << run.output;
  const std::size_t both_runs = KeyframeNames(server->address()).size();
  ASSERT_GT(both_runs, first_run);

  run = testing::RunObjmap("sessions --json --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json listed = nlohmann::json::parse(run.output.substr(run.output.find('{')));
  ASSERT_EQ(listed["sessions"].size(), 2u) << listed.dump(2);
  EXPECT_EQ(listed["current_session_id"], 2);
  const nlohmann::json& killed = listed["sessions"][0];
  const nlohmann::json& named = listed["sessions"][1];
  EXPECT_EQ(killed["name"], "session 1");
  EXPECT_EQ(killed["keyframes"], first_run);
  EXPECT_TRUE(killed["ended_s"].is_null()) << "a killed run has no end";
  EXPECT_EQ(named["name"], "second run");
  EXPECT_EQ(named["keyframes"], both_runs - first_run);
  EXPECT_EQ(named["current"], true);
  EXPECT_EQ(named["first_keyframe_id"], first_run + 1);

  run = testing::RunObjmap("sessions --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("second run"), std::string::npos) << run.output;
  run = testing::RunObjmap("status --server " + server->address());
  EXPECT_NE(run.output.find("second run"), std::string::npos) << run.output;
  run = testing::RunObjmap("sessions --start " + std::string(300, 'x') + " --server " +
                           server->address());
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("INVALID_ARGUMENT"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("300 bytes, at most 200"), std::string::npos) << run.output;
  run = testing::RunObjmap("sessions --start evening --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("started session 3 \"evening\""), std::string::npos) << run.output;
  server->Kill(SIGTERM);  // a clean stop stores the end of session 2 (and nothing of empty 3)
  server.reset();

  EXPECT_EQ(Query(db, "SELECT count(*) FROM sessions")[0], "2");
  EXPECT_EQ(Query(db, "SELECT count(*) FROM keyframes WHERE session_id = 2")[0],
            std::to_string(both_runs - first_run));
  EXPECT_EQ(Query(db, "SELECT ended_s IS NOT NULL FROM sessions WHERE id = 2")[0], "1");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace objmap
