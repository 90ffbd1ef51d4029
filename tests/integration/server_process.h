#pragma once
// The real objmap_server executable as a child process: started on a free loopback port
// (--listen 127.0.0.1:0), its address read from the one line it prints once it serves, its
// stderr kept in a log file, and stopped with SIGTERM or killed with SIGKILL.

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace objmap::testing {

class ServerProcess {
 public:
  /// `arguments` follow `--db db_path --listen 127.0.0.1:0`; stderr is appended to `log_path`.
  ServerProcess(std::string executable, std::string db_path, std::string log_path,
                std::vector<std::string> arguments)
      : executable_(std::move(executable)),
        db_path_(std::move(db_path)),
        log_path_(std::move(log_path)),
        arguments_(std::move(arguments)) {}
  ~ServerProcess() { Kill(SIGKILL); }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  /// Starts the server and waits (up to `timeout`, a restart rebuilds the map first) for its
  /// "objmap_server listening on ADDR ..." line. False with a reason (and the log) otherwise.
  bool Start(std::chrono::seconds timeout, std::string* why) {
    int out[2];
    if (pipe(out) != 0) {
      *why = "pipe failed";
      return false;
    }
    std::vector<std::string> argv_strings = {executable_, "--db", db_path_, "--listen",
                                             "127.0.0.1:0"};
    argv_strings.insert(argv_strings.end(), arguments_.begin(), arguments_.end());
    std::vector<char*> argv;
    for (std::string& argument : argv_strings) argv.push_back(argument.data());
    argv.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      dup2(out[1], STDOUT_FILENO);
      const int log = open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      if (log >= 0) dup2(log, STDERR_FILENO);
      close(out[0]);
      close(out[1]);
      execv(argv[0], argv.data());
      _exit(127);
    }
    close(out[1]);
    stdout_fd_ = out[0];
    if (pid_ < 0) {
      *why = "fork failed";
      return false;
    }
    std::string line;
    if (!ReadLine(timeout, &line)) {
      *why = "objmap_server printed no listening line within " + std::to_string(timeout.count()) +
             " s; its log:\n" + Log();
      Kill(SIGKILL);
      return false;
    }
    const std::string prefix = "objmap_server listening on ";
    if (line.rfind(prefix, 0) != 0) {
      *why = "unexpected first line '" + line + "'; log:\n" + Log();
      Kill(SIGKILL);
      return false;
    }
    address_ = line.substr(prefix.size(), line.find(' ', prefix.size()) - prefix.size());
    return true;
  }

  [[nodiscard]] const std::string& address() const { return address_; }
  [[nodiscard]] bool running() const { return pid_ > 0; }
  [[nodiscard]] pid_t pid() const { return pid_; }

  /// Sends `signal` and reaps the process; returns its exit code (or 128 + the signal).
  int Kill(int signal) {
    if (pid_ <= 0) return -1;
    ::kill(pid_, signal);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    if (stdout_fd_ >= 0) close(stdout_fd_);
    stdout_fd_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  [[nodiscard]] std::string Log() const {
    std::ifstream file(log_path_);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  }

 private:
  bool ReadLine(std::chrono::seconds timeout, std::string* line) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    line->clear();
    while (std::chrono::steady_clock::now() < deadline) {
      pollfd fd{stdout_fd_, POLLIN, 0};
      if (poll(&fd, 1, 200) <= 0) continue;
      char c = 0;
      if (read(stdout_fd_, &c, 1) != 1) return false;  // the server exited
      if (c == '\n') return true;
      line->push_back(c);
    }
    return false;
  }

  std::string executable_, db_path_, log_path_;
  std::vector<std::string> arguments_;
  pid_t pid_ = -1;
  int stdout_fd_ = -1;  // kept open: the server may print again, and must not get SIGPIPE
  std::string address_;
};

}  // namespace objmap::testing
