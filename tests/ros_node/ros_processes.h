#pragma once
// Real ROS processes for tests: a rosmaster on a free loopback port (stopped with SIGTERM, as
// roslaunch stops it) and ROS executables started against it, their output kept in a log file.

#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace objmap::testing {

/// A loopback TCP port no one listens on right now (the kernel's pick for port 0).
inline int FreeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof(address);
  int port = -1;
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    port = ntohs(address.sin_port);
  }
  close(fd);
  return port;
}

/// True once something accepts TCP connections on 127.0.0.1:`port`.
inline bool Accepts(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool connected = connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  close(fd);
  return connected;
}

/// A child process with stdout and stderr appended to a log file.
class ChildProcess {
 public:
  ChildProcess(std::vector<std::string> argv, std::string log_path)
      : argv_(std::move(argv)), log_path_(std::move(log_path)) {}
  ~ChildProcess() { Stop(SIGKILL); }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// Starts it with the current environment (ROS_MASTER_URI and the like set by the caller).
  bool Start(std::string* why) {
    pid_ = fork();
    if (pid_ == 0) {
      const int log = open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (log >= 0) {
        dup2(log, STDOUT_FILENO);
        dup2(log, STDERR_FILENO);
      }
      std::vector<char*> argv;
      for (std::string& argument : argv_) argv.push_back(argument.data());
      argv.push_back(nullptr);
      execvp(argv[0], argv.data());
      _exit(127);
    }
    if (pid_ < 0) {
      *why = "fork failed";
      return false;
    }
    return true;
  }

  /// The exit code once it has exited on its own within `timeout`; -1 while it still runs.
  int WaitForExit(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (pid_ > 0) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (std::chrono::steady_clock::now() > deadline) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }

  [[nodiscard]] bool running() {
    if (pid_ <= 0) return false;
    int status = 0;
    return waitpid(pid_, &status, WNOHANG) == 0;
  }

  /// Sends `signal` and reaps it (SIGKILL after 20 s); its exit code or 128 + the signal.
  int Stop(int signal) {
    if (pid_ <= 0) return -1;
    ::kill(pid_, signal);
    int code = WaitForExit(std::chrono::seconds(20));
    if (code < 0 && pid_ > 0) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
      pid_ = -1;
      code = 128 + SIGKILL;
    }
    return code;
  }

  [[nodiscard]] std::string Log() const {
    std::ifstream file(log_path_);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  }

 private:
  std::vector<std::string> argv_;
  std::string log_path_;
  pid_t pid_ = -1;
};

/// `rosmaster --core -p PORT` on a free port; sets ROS_MASTER_URI (and ROS_HOME, for logs) in
/// this process's environment so that ros::init and children started later use it.
class RosMaster {
 public:
  explicit RosMaster(const std::string& log_dir) : log_dir_(log_dir) {}
  ~RosMaster() { Stop(); }

  bool Start(std::string* why) {
    port_ = FreeLoopbackPort();
    if (port_ <= 0) {
      *why = "no free loopback port";
      return false;
    }
    const std::string uri = "http://127.0.0.1:" + std::to_string(port_);
    setenv("ROS_MASTER_URI", uri.c_str(), 1);
    setenv("ROS_HOME", log_dir_.c_str(), 1);
    setenv("ROS_LOG_DIR", log_dir_.c_str(), 1);
    setenv("ROS_IP", "127.0.0.1", 1);
    process_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{"rosmaster", "--core", "-p", std::to_string(port_)},
        log_dir_ + "/rosmaster.log");
    if (!process_->Start(why)) return false;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!Accepts(port_)) {
      if (!process_->running() || std::chrono::steady_clock::now() > deadline) {
        *why = "rosmaster did not start on port " + std::to_string(port_) + "; its log:\n" +
               process_->Log();
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return true;
  }

  void Stop() {
    if (process_) process_->Stop(SIGTERM);
    process_.reset();
  }

  [[nodiscard]] int port() const { return port_; }

 private:
  std::string log_dir_;
  int port_ = -1;
  std::unique_ptr<ChildProcess> process_;
};

}  // namespace objmap::testing
