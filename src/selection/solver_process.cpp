// A child process per solve: fork, pipes for the result and the child's standard error, a
// wall-clock kill when a limit is set, and an account of how the child ended.
#include "selection/solver_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "city3d/error.hpp"

namespace city3d::detail {
namespace {

// The child's file descriptors: 1 is /dev/null (CBC prints through stdio), 2 the standard-error pipe,
// 3 the result pipe; every other descriptor is closed, so no child holds another solve's pipes open.
constexpr int kResultFd = 3;

// How much of the child's standard error is kept for the message.
constexpr std::size_t kStderrKept = 2000;

bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

[[noreturn]] void child_main(const std::function<std::string()>& work, int result_fd, int stderr_fd) {
  // Die with the parent: a solve nobody waits for must not run on.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  const int devnull = ::open("/dev/null", O_WRONLY);
  if (devnull < 0 || ::dup2(devnull, 1) < 0 || ::dup2(stderr_fd, 2) < 0 || ::dup2(result_fd, kResultFd) < 0)
    ::_exit(120);
  if (::close_range(kResultFd + 1, ~0U, 0) != 0) {  // kernels before 5.9 lack it
    const long limit = std::min(::sysconf(_SC_OPEN_MAX), 65536L);
    for (int fd = kResultFd + 1; fd < limit; ++fd) ::close(fd);
  }
  std::string output;
  try {
    output = work();
  } catch (const std::exception& e) {
    const std::string text = std::string("exception: ") + e.what() + "\n";
    write_all(2, text.data(), text.size());
    ::_exit(121);
  } catch (...) {
    ::_exit(122);
  }
  // A length first, so the parent can tell a whole result from one cut short.
  const std::uint64_t size = output.size();
  if (!write_all(kResultFd, reinterpret_cast<const char*>(&size), sizeof size) ||
      !write_all(kResultFd, output.data(), output.size()))
    ::_exit(123);
  ::_exit(0);
}

std::string describe_end(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::sigdescr_np(sig);
    return "was killed by signal " + std::to_string(sig) + (name ? std::string(" (") + name + ")" : std::string());
  }
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  return "ended with status " + std::to_string(status);
}

// CPU seconds of the children this thread has waited for.
thread_local double children_cpu = 0.0;

}  // namespace

double children_cpu_seconds() { return children_cpu; }

ChildResult run_in_child(const std::function<std::string()>& work, double time_limit) {
  int result_pipe[2], stderr_pipe[2];
  if (::pipe2(result_pipe, O_CLOEXEC) != 0)
    throw ReconstructionError(ReconstructionStage::selection, std::string("cannot make a pipe for the solver process: ") + std::strerror(errno));
  if (::pipe2(stderr_pipe, O_CLOEXEC) != 0) {
    const int error = errno;
    ::close(result_pipe[0]);
    ::close(result_pipe[1]);
    throw ReconstructionError(ReconstructionStage::selection, std::string("cannot make a pipe for the solver process: ") + std::strerror(error));
  }
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) child_main(work, result_pipe[1], stderr_pipe[1]);
  const int fork_error = errno;
  ::close(result_pipe[1]);
  ::close(stderr_pipe[1]);
  if (pid < 0) {
    ::close(result_pipe[0]);
    ::close(stderr_pipe[0]);
    throw ReconstructionError(ReconstructionStage::selection, std::string("cannot start the solver process: ") + std::strerror(fork_error));
  }

  ChildResult result;
  std::string received, errors;
  pollfd fds[2] = {{result_pipe[0], POLLIN, 0}, {stderr_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&received, &errors};
  int open = 2;
  const bool limited = time_limit > 0 && std::isfinite(time_limit);
  char buffer[65536];
  while (open > 0) {
    int wait_ms = -1;
    if (limited) {
      const double left = time_limit - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left <= 0) {
        result.timed_out = true;
        break;
      }
      wait_ms = static_cast<int>(std::ceil(std::min(left, 3600.0) * 1000.0));
    }
    const int ready = ::poll(fds, 2, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) break;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || fds[k].revents == 0) continue;
      const ssize_t n = ::read(fds[k].fd, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        ::close(fds[k].fd);
        fds[k].fd = -1;  // poll ignores negative descriptors
        --open;
        continue;
      }
      sinks[k]->append(buffer, static_cast<std::size_t>(n));
      if (k == 1 && errors.size() > 4 * kStderrKept) errors.erase(0, errors.size() - kStderrKept);
    }
  }
  if (result.timed_out) ::kill(pid, SIGKILL);
  for (pollfd& p : fds)
    if (p.fd >= 0) ::close(p.fd);
  int status = 0;
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  children_cpu += usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);

  if (errors.size() > kStderrKept) errors.erase(0, errors.size() - kStderrKept);
  while (!errors.empty() && (errors.back() == '\n' || errors.back() == '\r')) errors.pop_back();
  result.stderr_tail = errors;
  std::uint64_t size = 0;
  const bool whole = received.size() >= sizeof size &&
                     (std::memcpy(&size, received.data(), sizeof size), received.size() - sizeof size == size);
  if (!result.timed_out && WIFEXITED(status) && WEXITSTATUS(status) == 0 && whole) {
    result.completed = true;
    result.output = received.substr(sizeof size);
  } else if (result.timed_out) {
    result.failure = "killed at the time limit of " + std::to_string(time_limit) + " s";
  } else {
    result.failure = describe_end(status);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) result.failure += ", but its result came cut short";
  }
  return result;
}

}  // namespace city3d::detail
