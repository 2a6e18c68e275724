#include "engine/archive/archive_probe.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <vector>

#include "engine/archive/archive_error.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"

namespace gesweep::archive {
namespace {

bool in_child = false;

// The report of a child whose probe returned.
constexpr char kFinished = 'F';

// The child's report: a kind byte, then each field as its length (8 decimal digits) and its bytes.
std::string Encode(char kind, std::initializer_list<std::string> fields) {
  std::string out(1, kind);
  for (const std::string& field : fields) {
    char length[16];
    std::snprintf(length, sizeof length, "%08zu", field.size());
    out += length;
    out += field;
  }
  return out;
}

std::vector<std::string> Decode(const std::string& report) {
  std::vector<std::string> fields;
  std::size_t at = 1;
  while (at + 8 <= report.size()) {
    const std::size_t length = std::strtoul(report.substr(at, 8).c_str(), nullptr, 10);
    at += 8;
    if (at + length > report.size()) break;
    fields.push_back(report.substr(at, length));
    at += length;
  }
  return fields;
}

// Whether `report` holds all of a report: the finished byte, or a kind and all of its fields.
bool Complete(const std::string& report) {
  if (report.empty()) return false;
  if (report[0] == kFinished) return report.size() == 1;
  std::size_t expected = 0;
  switch (report[0]) {
    case 'R':
      expected = 7;
      break;
    case 'I':
      expected = 5;
      break;
    case 'A':
      expected = 2;
      break;
    default:
      expected = 1;
  }
  std::size_t at = 1, fields = 0;
  while (at + 8 <= report.size()) {
    const std::size_t length = std::strtoul(report.substr(at, 8).c_str(), nullptr, 10);
    if (at + 8 + length > report.size()) return false;
    at += 8 + length;
    ++fields;
  }
  return fields == expected && at == report.size();
}

// Everything the child does before it calls the probe is async-signal-safe (the parent may have
// other threads: Python's, TBB's): system calls only, no allocation, no lock.
[[noreturn]] void ChildMain(int report_fd, pid_t parent, const std::function<void()>& probe,
                            double deadline_s) {
  in_child = true;
  const int null_fd = ::open("/dev/null", O_RDWR | O_CLOEXEC);
  if (null_fd >= 0) {
    ::dup2(null_fd, STDOUT_FILENO);
    ::dup2(null_fd, STDERR_FILENO);
  }
  const struct rlimit no_core { 0, 0 };
  ::setrlimit(RLIMIT_CORE, &no_core);
  // Ended with the parent (a parent killed while it waits must not leave a child looping for ever)
  // and, as a second bound, by an alarm a little after the parent's deadline.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(3);  // the parent died before prctl took effect
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  struct sigaction fallback {};
  fallback.sa_handler = SIG_DFL;
  for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) ::sigaction(s, &ignore, nullptr);
  // A crash ends the child at once, silently: not through a handler the parent installed (Python's
  // faulthandler would print a traceback to its own copy of the terminal).
  for (int s : {SIGALRM, SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) ::sigaction(s, &fallback, nullptr);
  ::alarm(static_cast<unsigned>(std::ceil(deadline_s)) + 2);
  std::string report;
  try {
    probe();
    report = std::string(1, kFinished);
  } catch (const RequestError& e) {
    report = Encode('R', {e.source(), e.key(), e.value(), e.expected(), std::to_string(e.line()), e.remedy(),
                          e.remedy_argument()});
  } catch (const InputError& e) {
    report = Encode('I', {e.source(), e.key(), e.value(), e.expected(), std::to_string(e.line())});
  } catch (const ArchiveError& e) {
    report = Encode('A', {e.what(), e.cause()});
  } catch (const std::exception& e) {
    report = Encode('O', {e.what()});
  } catch (...) {
    report = Encode('O', {"unknown error"});
  }
  std::size_t done = 0;
  while (done < report.size()) {
    const ssize_t written = ::write(report_fd, report.data() + done, report.size() - done);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) ::_exit(3);
    done += static_cast<std::size_t>(written);
  }
  ::_exit(0);
}

// How a child's wait ended.
struct ChildWait {
  std::string report;
  int status = 0;  // waitpid's, when reaped
  bool timed_out = false;
  bool reaped = false;
};

// Reads the child's report from `report_fd` until it is complete, or the child has gone: not until
// end of file alone, since a fork made meanwhile by another thread (a second check) holds a copy of
// the pipe's write end. Gives up at `deadline` (timed_out).
ChildWait ReadReport(int report_fd, pid_t child, std::chrono::steady_clock::time_point deadline) {
  ChildWait wait;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      wait.timed_out = true;
      break;
    }
    struct pollfd wait_for {
      report_fd, POLLIN, 0
    };
    const int ready = ::poll(&wait_for, 1, static_cast<int>(std::min<long long>(left.count() + 1, 20)));
    if (ready < 0 && errno != EINTR) break;
    if (ready > 0) {
      char buffer[4096];
      const ssize_t got = ::read(report_fd, buffer, sizeof buffer);
      if (got > 0) {
        wait.report.append(buffer, static_cast<std::size_t>(got));
        if (Complete(wait.report)) break;
        continue;
      }
      if (got == 0) break;  // end of file: every write end closed
      if (errno != EINTR) break;
    }
    if (::waitpid(child, &wait.status, WNOHANG) == child) {
      wait.reaped = true;
      ::fcntl(report_fd, F_SETFL, O_NONBLOCK);  // what it wrote before it went
      char buffer[4096];
      for (ssize_t got; (got = ::read(report_fd, buffer, sizeof buffer)) > 0;) {
        wait.report.append(buffer, static_cast<std::size_t>(got));
      }
      break;
    }
  }
  return wait;
}

// The error a child reported (kind R, I, A or O), rebuilt in this process: into outcome.error (and
// outcome.remedy for a RequestError).
void RebuildError(const std::string& report, ProbeOutcome& outcome) {
  const std::vector<std::string> f = Decode(report);
  const auto field = [&f](std::size_t i) { return i < f.size() ? f[i] : std::string(); };
  const int line = std::atoi(field(4).c_str());
  outcome.kind = ProbeOutcome::Kind::kThrew;
  if (report[0] == 'R') {
    outcome.error =
        std::make_exception_ptr(RequestError(field(0), field(1), field(2), field(3), field(5), field(6)));
    outcome.remedy = field(5);
  } else if (report[0] == 'I') {
    outcome.error = std::make_exception_ptr(InputError(field(0), field(1), field(2), field(3), line));
  } else if (report[0] == 'A') {
    outcome.error = std::make_exception_ptr(ArchiveError(field(0), field(1)));
  } else {
    outcome.error = std::make_exception_ptr(ArchiveError(field(0)));
  }
}

// The outcome of a child reaped after `wait`: timed out, killed by a signal, exited without a whole
// report, finished, or threw.
ProbeOutcome OutcomeOf(const ChildWait& wait) {
  ProbeOutcome outcome;
  const int status = wait.status;
  std::string report = wait.report;
  if (!Complete(report)) report.clear();
  if (wait.timed_out) {
    outcome.kind = ProbeOutcome::Kind::kTimedOut;
  } else if (WIFSIGNALED(status)) {
    outcome.kind = ProbeOutcome::Kind::kSignal;
    outcome.signal = WTERMSIG(status);
  } else if (report.empty() || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    outcome.kind = ProbeOutcome::Kind::kExited;
    outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  } else if (report[0] == kFinished) {
    outcome.kind = ProbeOutcome::Kind::kFinished;
  } else {
    RebuildError(report, outcome);
  }
  return outcome;
}

}  // namespace

bool InProbeChild() { return in_child; }

ProbeOutcome RunInChild(const std::function<void()>& probe, double deadline_s) {
  ProbeOutcome outcome;
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
    outcome.kind = ProbeOutcome::Kind::kNoProcess;
    return outcome;
  }
  const pid_t parent = ::getpid();
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    outcome.kind = ProbeOutcome::Kind::kNoProcess;
    return outcome;
  }
  if (child == 0) {
    ::close(pipe_fds[0]);
    ChildMain(pipe_fds[1], parent, probe, deadline_s);
  }
  ::close(pipe_fds[1]);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                             std::chrono::duration<double>(deadline_s));
  ChildWait wait = ReadReport(pipe_fds[0], child, deadline);
  ::close(pipe_fds[0]);
  if (wait.timed_out) ::kill(child, SIGKILL);
  while (!wait.reaped && ::waitpid(child, &wait.status, 0) < 0 && errno == EINTR) {
  }
  return OutcomeOf(wait);
}

double ArchiveCheckDeadline() {
  constexpr double kDefaultSeconds = 3.0;
  const char* text = std::getenv("GESWEEP_ARCHIVE_CHECK_S");
  if (text == nullptr || *text == '\0') return kDefaultSeconds;
  char* end = nullptr;
  errno = 0;
  const double seconds = std::strtod(text, &end);
  if (end == text || *end != '\0' || errno != 0 || !(seconds == 0 || (seconds >= 0.1 && seconds <= 3600))) {
    throw InputError("environment", "GESWEEP_ARCHIVE_CHECK_S", EscapeForMessage(text),
                     "expected the archive check's deadline in seconds, in [0.1, 3600], or 0 to turn the "
                     "check off");
  }
  return seconds;
}

void GuardArchiveDecode(const std::string& shown, const std::function<void()>& probe,
                        const std::string& pass_remedy) {
  if (in_child) return;
  const double deadline_s = ArchiveCheckDeadline();
  if (deadline_s == 0) return;
  ProbeOutcome outcome = RunInChild(probe, deadline_s);
  constexpr const char* kDamaged = ": a damaged archive (docs/reliability.md, 11.4)";
  switch (outcome.kind) {
    case ProbeOutcome::Kind::kFinished:
    case ProbeOutcome::Kind::kNoProcess:
      return;
    case ProbeOutcome::Kind::kThrew:
      // Refused in the child: refused here in the same words, without decoding the file again (on a
      // damaged structure libhdf5 may fail cleanly once and crash the next time: a bad free).
      if (!outcome.remedy.empty() && outcome.remedy == pass_remedy) return;
      std::rethrow_exception(outcome.error);
    case ProbeOutcome::Kind::kSignal: {
      const char* name = sigabbrev_np(outcome.signal);
      const std::string signal =
          name != nullptr ? "SIG" + std::string(name) : "signal " + std::to_string(outcome.signal);
      throw InputError(shown, "", "", "libhdf5 crashed (" + signal + ") while decoding the file" + kDamaged);
    }
    case ProbeOutcome::Kind::kExited:
      throw InputError(shown, "", "",
                       "libhdf5 failed (the check's process exited with code " +
                           std::to_string(outcome.exit_code) + ") while decoding the file" + kDamaged);
    case ProbeOutcome::Kind::kTimedOut:
      throw InputError(shown, "", "",
                       "libhdf5 did not finish decoding the file within " + ShortNumber(deadline_s) +
                           " s: a damaged archive (docs/reliability.md, 11.4; GESWEEP_ARCHIVE_CHECK_S sets "
                           "the deadline)");
  }
  GESWEEP_UNREACHABLE();
}

}  // namespace gesweep::archive
