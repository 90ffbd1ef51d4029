#include "server_common.h"

#include <cmath>
#include <cstdio>
#include <iostream>

namespace objmap::cli {
namespace {

// Adding 0.0 turns -0.0 into 0.0.
Json PointJson(const v1::Vec3& p) { return Json::array({p.x() + 0.0, p.y() + 0.0, p.z() + 0.0}); }

}  // namespace

std::set<std::string> WithServerFlags(std::set<std::string> flags) {
  for (const char* flag :
       {"--server", "--timeout", "--tls-ca", "--tls-cert", "--tls-key", "--token-file"}) {
    flags.insert(flag);
  }
  return flags;
}

std::unique_ptr<MapClient> MakeClient(Arguments& args, double default_timeout_s,
                                      const MapClientOptions& base) {
  MapClientOptions options = base;
  options.deadline_s = args.GetNumber("--timeout", default_timeout_s);
  if (options.deadline_s < 0.0) {
    args.SetError("--timeout expects seconds >= 0, got '" + args.Get("--timeout", "") + "'");
    options.deadline_s = default_timeout_s;
  }
  options.tls_ca_path = args.Get("--tls-ca", "");
  options.tls_cert_path = args.Get("--tls-cert", "");
  options.tls_key_path = args.Get("--tls-key", "");
  const std::string token_file = args.Get("--token-file", "");
  std::string why;
  if (!token_file.empty() && !ReadTokenFile(token_file, &options.token, &why)) {
    args.SetError("--token-file: " + why);
  }
  return std::make_unique<MapClient>(args.Get("--server", kDefaultServer), options);
}

int FailWithStatus(const std::string& command, const grpc::Status& status) {
  std::cerr << "objmap " << command << ": " << DescribeStatus(status) << "\n";
  return kExitError;
}

int Fail(const std::string& command, const std::string& message) {
  std::cerr << "objmap " << command << ": " << message << "\n";
  return kExitError;
}

int UsageError(const Arguments& args, const std::string& usage) {
  std::cerr << (args.error().empty() ? "" : args.error() + "\n") << usage;
  return kExitUsage;
}

double Rounded(float value) { return std::round(static_cast<double>(value) * 1e4) / 1e4; }

std::string FormatPoint(const v1::Vec3& p) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.3f, %.3f, %.3f)", p.x() + 0.0, p.y() + 0.0, p.z() + 0.0);
  return text;
}

Json ObjectJson(const v1::Object& object) {
  Json scores = Json::array();
  for (const v1::ClassScore& score : object.scores()) {
    scores.push_back({{"class", score.class_name()}, {"score", Rounded(score.score())}});
  }
  Json json = {{"id", object.id()},
               {"class", object.class_name()},
               {"class_id", object.class_id()},
               {"confidence", Rounded(object.confidence())},
               {"centroid", PointJson(object.centroid())},
               {"bounds",
                {{"min", PointJson(object.bounds().min())},
                 {"max", PointJson(object.bounds().max())}}},
               {"observations", object.observations()},
               {"keyframes",
                std::vector<std::int64_t>(object.keyframes().begin(), object.keyframes().end())},
               {"confirmed", object.confirmed()},
               {"changed_version", object.changed_version()},
               {"scores", scores}};
  auto seen_json = [](const v1::Seen& seen) {
    return Json{{"keyframe_id", seen.keyframe_id()},
                {"session_id", seen.session_id()},
                {"stamp", seen.stamp()}};
  };
  if (object.has_first_seen()) {
    json["first_seen"] = seen_json(object.first_seen());
    json["last_seen"] = seen_json(object.last_seen());
  }
  if (object.has_last_seen_absent()) json["last_seen_absent"] = seen_json(object.last_seen_absent());
  return json;
}

}  // namespace objmap::cli
