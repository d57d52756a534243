// spherechain import — a third-party parser in a child process (import.h ImportOptions::isolate_assimp).
//
// assimp's parsers are not ours to fix: fuzzing found inputs on which one never returns (a PLY reader loop),
// and a crash inside one would end the caller. ImportInChild forks, runs the importer in the child, and
// reads back its Result<Mesh> (and the log lines and files read of its Context) through a pipe. The parent
// waits at most the time limit, then kills the child; a child that dies or is killed is a kFormat error
// naming what happened, never the caller's death. The child ends with _exit (no destructors, atexit
// handlers or leak check: its heap is the parent's copy).
#include "import_internal.h"

#if defined(__linux__)  // fork, pipe2 and poll; elsewhere assimp runs in the caller's process (below)
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

#if defined(__SANITIZE_ADDRESS__)
#define SPHERECHAIN_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SPHERECHAIN_ASAN 1
#endif
#endif
#ifdef SPHERECHAIN_ASAN
#include <sanitizer/common_interface_defs.h>
#endif

namespace spherechain::import::detail {
namespace {


// The child's end of the pipe, for ChildPhase (-1 in the parent and in-process).
int g_child_fd = -1;

bool WriteAll(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// ---------------------------------------------------------------------------------------------------
// The child's answer: a flat little-endian-as-the-machine byte string (parent and child are one binary).

struct Writer {
  std::string out;
  template <class T>
  void Pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void Str(const std::string& s) {
    Pod(uint64_t{s.size()});
    out += s;
  }
  template <class T>
  void Vec(const std::vector<T>& v) {
    Pod(uint64_t{v.size()});
    if (!v.empty()) out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
};

struct Reader {
  const std::string& in;
  size_t at = 0;
  bool ok = true;
  template <class T>
  T Pod() {
    T v{};
    if (in.size() - at < sizeof v) return ok = false, v;
    std::memcpy(&v, in.data() + at, sizeof v);
    at += sizeof v;
    return v;
  }
  std::string Str() {
    const uint64_t n = Pod<uint64_t>();
    if (!ok || in.size() - at < n) return ok = false, std::string();
    std::string s = in.substr(at, n);
    at += n;
    return s;
  }
  template <class T>
  std::vector<T> Vec() {
    const uint64_t n = Pod<uint64_t>();
    if (!ok || (in.size() - at) / sizeof(T) < n) return ok = false, std::vector<T>();
    std::vector<T> v(n);
    if (n != 0) std::memcpy(v.data(), in.data() + at, n * sizeof(T));  // an empty vector's data() may be null
    at += n * sizeof(T);
    return v;
  }
};

struct LogLine {
  Context::Level level;
  std::string text;
};

std::string Encode(const Result<Mesh>& r, const std::vector<LogLine>& log, const Context& child) {
  Writer w;
  w.Pod(uint64_t{log.size()});
  for (const LogLine& l : log) w.Pod(l.level), w.Str(l.text);
  w.Pod(uint64_t{child.files_read.size()});
  for (const std::string& f : child.files_read) w.Str(f);
  w.Pod(uint8_t{r.ok()});
  if (!r.ok()) {
    w.Pod(r.error().code);
    w.Str(r.error().message);
    return std::move(w.out);
  }
  const Mesh& m = r.value();
  w.Vec(m.positions);
  w.Vec(m.indices);
  w.Pod(uint64_t{m.parts.size()});
  for (const MeshPart& p : m.parts)
    w.Str(p.name), w.Pod(p.first_vertex), w.Pod(p.vertex_count), w.Pod(p.first_triangle), w.Pod(p.triangle_count);
  w.Str(m.source_path), w.Str(m.source_format), w.Str(m.units), w.Pod(m.unit_scale_m), w.Pod(m.up_axis);
  w.Str(m.vertex_contract), w.Pod(m.source_vertex_count), w.Pod(m.joined_vertex_count);
  w.Pod(uint8_t{m.skin.has_value()});
  if (m.skin) {
    w.Pod(uint64_t{m.skin->nodes.size()});
    for (const Node& n : m.skin->nodes) w.Str(n.name), w.Pod(n.parent), w.Pod(n.translation), w.Pod(n.rotation), w.Pod(n.scale);
    w.Vec(m.skin->joints);
    w.Vec(m.skin->weight_offsets), w.Vec(m.skin->weight_joints), w.Vec(m.skin->weights), w.Str(m.skin->source);
  }
  w.Pod(uint64_t{m.clips.size()});
  for (const Clip& c : m.clips) {
    w.Str(c.name), w.Pod(c.duration_s), w.Pod(uint64_t{c.channels.size()});
    for (const Channel& ch : c.channels) w.Pod(ch.node), w.Pod(ch.path), w.Pod(ch.interpolation), w.Vec(ch.times), w.Vec(ch.values);
  }
  return std::move(w.out);
}

/// Decodes Encode's bytes, replaying the log lines and files read into `ctx`. False when they are cut short.
bool Decode(const std::string& bytes, Context* ctx, Result<Mesh>* out) {
  Reader r{bytes};
  const uint64_t nlog = r.Pod<uint64_t>();
  for (uint64_t i = 0; r.ok && i < nlog; ++i) {
    const auto level = r.Pod<Context::Level>();
    const std::string text = r.Str();
    if (r.ok && ctx) ctx->Log(level, text);
  }
  const uint64_t nfiles = r.Pod<uint64_t>();
  for (uint64_t i = 0; r.ok && i < nfiles; ++i) {
    const std::string f = r.Str();
    if (r.ok && ctx) ctx->RecordFileRead(f);
  }
  if (!r.Pod<uint8_t>()) {
    const auto code = r.Pod<Error::Code>();
    *out = MakeError(code, r.Str());
    return r.ok;
  }
  Mesh m;
  m.positions = r.Vec<float>();
  m.indices = r.Vec<uint32_t>();
  const uint64_t nparts = r.Pod<uint64_t>();
  for (uint64_t i = 0; r.ok && i < nparts; ++i) {
    MeshPart p;
    p.name = r.Str();
    p.first_vertex = r.Pod<uint32_t>(), p.vertex_count = r.Pod<uint32_t>();
    p.first_triangle = r.Pod<uint32_t>(), p.triangle_count = r.Pod<uint32_t>();
    m.parts.push_back(std::move(p));
  }
  m.source_path = r.Str(), m.source_format = r.Str(), m.units = r.Str();
  m.unit_scale_m = r.Pod<float>(), m.up_axis = r.Pod<UpAxis>();
  m.vertex_contract = r.Str(), m.source_vertex_count = r.Pod<uint32_t>(), m.joined_vertex_count = r.Pod<uint32_t>();
  if (r.Pod<uint8_t>()) {
    Skin s;
    const uint64_t nnodes = r.Pod<uint64_t>();
    for (uint64_t i = 0; r.ok && i < nnodes; ++i) {
      Node n;
      n.name = r.Str(), n.parent = r.Pod<int32_t>();
      n.translation = r.Pod<std::array<float, 3>>(), n.rotation = r.Pod<std::array<float, 4>>(), n.scale = r.Pod<std::array<float, 3>>();
      s.nodes.push_back(std::move(n));
    }
    s.joints = r.Vec<SkinJoint>();
    s.weight_offsets = r.Vec<uint32_t>(), s.weight_joints = r.Vec<uint32_t>(), s.weights = r.Vec<float>(), s.source = r.Str();
    m.skin = std::move(s);
  }
  const uint64_t nclips = r.Pod<uint64_t>();
  for (uint64_t i = 0; r.ok && i < nclips; ++i) {
    Clip c;
    c.name = r.Str(), c.duration_s = r.Pod<float>();
    const uint64_t nch = r.Pod<uint64_t>();
    for (uint64_t k = 0; r.ok && k < nch; ++k) {
      Channel ch;
      ch.node = r.Pod<int32_t>(), ch.path = r.Pod<Channel::Path>(), ch.interpolation = r.Pod<Channel::Interpolation>();
      ch.times = r.Vec<float>(), ch.values = r.Vec<float>();
      c.channels.push_back(std::move(ch));
    }
    m.clips.push_back(std::move(c));
  }
  if (!r.ok || r.at != bytes.size()) return false;
  *out = std::move(m);
  return true;
}

[[noreturn]] void RunChild(int fd, const std::string& path, const ImportOptions& options, ChildImporter import,
                           const sigset_t& mask_before_fork) {
  g_child_fd = fd;
  // A crash in the child is its death and nothing more: the host's handlers, inherited through fork (a crash
  // reporter, a sanitizer's or libFuzzer's report and artifact), must not run for it. The parent names the
  // signal or the exit status.
  for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS}) ::signal(sig, SIG_DFL);
  // So is an ending signal the host handles (a Ctrl-C reaches the whole process group; the CLI's handler removes
  // its output temporaries, in the parent only): blocked across the fork (ImportInChild), its handler replaced
  // before it is unblocked, so the host's handler never runs here. One the host ignores stays ignored.
  for (const int sig : kEndingSignals) {
    struct sigaction old = {};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler != SIG_IGN) ::signal(sig, SIG_DFL);
  }
  ::pthread_sigmask(SIG_SETMASK, &mask_before_fork, nullptr);
#ifdef SPHERECHAIN_ASAN
  __sanitizer_set_death_callback(nullptr);  // ASan's own reports (an interceptor's) end the child with exit 1
#endif
  const double seconds = std::max(1.0, options.assimp_seconds);
  const rlimit cpu{static_cast<rlim_t>(std::ceil(seconds)) + 1, static_cast<rlim_t>(std::ceil(seconds)) + 2};
  ::setrlimit(RLIMIT_CPU, &cpu);  // a backstop: the parent's clock decides
#ifndef SPHERECHAIN_ASAN  // ASan reserves terabytes of address space for its shadow: no RLIMIT_AS under it
  if (options.assimp_memory_bytes > 0) {
    const rlimit as{options.assimp_memory_bytes, options.assimp_memory_bytes};
    ::setrlimit(RLIMIT_AS, &as);
  }
#endif
  std::vector<LogLine> log;
  Context child;
  child.sink = [&log](Context::Level level, const std::string& text) { log.push_back({level, text}); };
  std::string bytes;
  try {
    bytes = Encode(import(path, options, &child), log, child);
  } catch (...) {
    bytes = Encode(FileError(Error::Code::kFormat, path, "import failed in the parser's process"), log, child);
  }
  const uint64_t size = bytes.size();
  const char done = 'D';
  const bool ok = WriteAll(fd, &done, 1) && WriteAll(fd, &size, sizeof size) && WriteAll(fd, bytes.data(), bytes.size());
  ::_exit(ok ? 0 : 3);
}

std::string DeathText(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::strsignal(sig);
    return "signal " + std::to_string(sig) + (name ? std::string(" (") + name + ")" : std::string());
  }
  return "exit status " + std::to_string(WEXITSTATUS(status));
}

}  // namespace

void ChildPhase(char phase) {
  if (g_child_fd >= 0) WriteAll(g_child_fd, &phase, 1);
}

Result<Mesh> ImportInChild(const std::string& path, const ImportOptions& options, Context* ctx, ChildImporter import) {
  int fds[2];
  pid_t pid = -1;
  {
    // From the pipe to the parent's close of its write end, no other import forks: a child forked by
    // another thread in between (a batch bake, -j) would hold this pipe's write end (the child never
    // execs, so O_CLOEXEC does not close it), and this import would wait for that child's end.
    static std::mutex fork_mutex;
    std::lock_guard<std::mutex> lock(fork_mutex);
    if (::pipe2(fds, O_CLOEXEC) != 0)
      return FileError(Error::Code::kInternal, path, std::string("cannot start the parser's process: pipe: ") + std::strerror(errno));
    std::fflush(nullptr);
    const sigset_t ending = EndingSignalSet();
    sigset_t mask;
    ::pthread_sigmask(SIG_BLOCK, &ending, &mask);
    pid = ::fork();
    if (pid != 0) ::pthread_sigmask(SIG_SETMASK, &mask, nullptr);
    if (pid < 0) {
      ::close(fds[0]);
      ::close(fds[1]);
      return FileError(Error::Code::kInternal, path, std::string("cannot start the parser's process: fork: ") + std::strerror(errno));
    }
    if (pid == 0) {
      ::close(fds[0]);
      RunChild(fds[1], path, options, import, mask);
    }
    ::close(fds[1]);
  }

  // Read what the child sends until it closes the pipe or the time is up. Phases: 'R' reading with the
  // parser, 'C' converting its scene, then 'D', the size and the answer.
  using Clock = std::chrono::steady_clock;
  const double seconds = std::max(0.001, options.assimp_seconds);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  std::string got;
  char phase = 'R';
  bool timed_out = false;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int n = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) continue;
    char buf[1 << 16];
    const ssize_t r = ::read(fds[0], buf, sizeof buf);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;  // the child closed the pipe (it ended)
    got.append(buf, static_cast<size_t>(r));
    while (!got.empty() && got[0] != 'D') phase = got[0], got.erase(0, 1);
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const char* doing = phase == 'C' ? "converting assimp's scene" : "reading it";
  if (timed_out) {
    char limit[32];
    std::snprintf(limit, sizeof limit, "%g", seconds);
    return FileError(Error::Code::kFormat, path,
                     std::string("assimp did not finish ") + doing + " within " + limit + " s (its process was stopped)");
  }
  uint64_t size = 0;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && got.size() >= 1 + sizeof size) {
    std::memcpy(&size, got.data() + 1, sizeof size);
    Result<Mesh> out = MakeError(Error::Code::kInternal, path + ": not imported");
    if (got.size() - 1 - sizeof size == size && Decode(got.substr(1 + sizeof size), ctx, &out)) return out;
  }
  return FileError(Error::Code::kFormat, path,
                   std::string("the assimp importer's process died ") + doing + " (" + DeathText(status) +
                       "): the file is not readable");
}

}  // namespace spherechain::import::detail

#else  // not Linux: no child process; the import runs in this process, as with isolate_assimp false

namespace spherechain::import::detail {

void ChildPhase(char) {}

Result<Mesh> ImportInChild(const std::string& path, const ImportOptions& options, Context* ctx, ChildImporter import) {
  return import(path, options, ctx);
}

}  // namespace spherechain::import::detail

#endif
