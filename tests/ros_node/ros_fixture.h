#pragma once
// A gtest fixture with a rosmaster of its own (a free loopback port, a temporary folder for logs
// and databases) and this test process connected to it as a ROS node. Suites derive from it and
// call StartRos(name) in SetUpTestSuite and StopRos() in TearDownTestSuite.

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "ros_node/ros_processes.h"

namespace objmap::testing {

class RosFixture : public ::testing::Test {
 protected:
  static void StartRos(const std::string& name) {
    dir() = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(getpid()));
    std::filesystem::remove_all(dir());
    std::filesystem::create_directories(dir());
    master() = std::make_unique<RosMaster>(dir().string());
    std::string why;
    if (!master()->Start(&why)) {
      setup_error() = why;
      return;
    }
    int argc = 0;
    ros::init(argc, nullptr, name,
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    ros::start();
  }

  static void StopRos() {
    if (ros::isStarted()) ros::shutdown();
    if (master()) master()->Stop();
    master().reset();
    std::filesystem::remove_all(dir());
  }

  void SetUp() override { ASSERT_TRUE(setup_error().empty()) << setup_error(); }

  static std::filesystem::path& dir() {
    static std::filesystem::path path;
    return path;
  }
  static std::unique_ptr<RosMaster>& master() {
    static std::unique_ptr<RosMaster> instance;
    return instance;
  }
  static std::string& setup_error() {
    static std::string text;
    return text;
  }

  /// Waits (up to 120 s, while `process` runs) until `service` is advertised.
  static bool WaitForService(const std::string& service, ChildProcess* process) {
    for (int i = 0; i < 600 && process->running(); ++i) {
      if (ros::service::waitForService(service, ros::Duration(0.2))) return true;
    }
    return false;
  }
};

}  // namespace objmap::testing
