// spherechain import — files and identities: whole-file reads, atomic writes, the mesh fingerprint an
// asset records, weld ids, XXH3 hashes, and reading a .sphc into aligned memory.
#include "spherechain/import/file_io.h"

#include "import_internal.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <fstream>
#include <numeric>
#include <cerrno>
#include <cstring>
#include <system_error>

#include <pthread.h>
#include <signal.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <xxhash.h>

namespace spherechain::import {

uint64_t Hash64(const void* data, size_t size) { return XXH3_64bits(data, size); }

Fingerprint ComputeFingerprint(const Mesh& mesh) {
  Fingerprint f;
  f.vertex_count = mesh.vertex_count();
  f.triangle_count = mesh.triangle_count();
  f.positions_hash = Hash64(mesh.positions.data(), mesh.positions.size() * sizeof(float));
  f.indices_hash = Hash64(mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  return f;
}

std::vector<uint32_t> ComputeWeldIds(const std::vector<float>& positions) {
  const uint32_t n = static_cast<uint32_t>(positions.size() / 3);
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  const auto key = [&](uint32_t v) {
    return std::array<float, 3>{positions[3 * size_t{v}], positions[3 * size_t{v} + 1], positions[3 * size_t{v} + 2]};
  };
  // Sort by position, then index: each run of equal positions starts with its lowest index.
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const auto ka = key(a), kb = key(b);
    return ka != kb ? ka < kb : a < b;
  });
  std::vector<uint32_t> weld(n);
  for (uint32_t i = 0; i < n;) {
    uint32_t j = i;
    while (j < n && key(order[j]) == key(order[i])) weld[order[j++]] = order[i];
    i = j;
  }
  return weld;
}

namespace {

// The folder `path` is written in, or an error naming it when it does not exist.
Status OutputFolderExists(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    return MakeError(Error::Code::kIo, "cannot write '" + path + "': folder '" + dir.string() + "' does not exist");
  return Ok{};
}

// `bytes` written whole through `fd` (the file `tmp`, just created), flushed to the disk and closed; on failure the
// file is removed.
Status WriteWhole(int fd, const std::string& tmp, const void* bytes, size_t size) {
  const char* at = static_cast<const char*>(bytes);
  size_t left = size;
  bool ok = true;
  while (ok && left > 0) {
    const ssize_t n = ::write(fd, at, left);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) at += n, left -= static_cast<size_t>(n);
  }
  ok = ok && ::fsync(fd) == 0;
  const bool closed = ::close(fd) == 0;
  if (!ok || !closed) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    return MakeError(Error::Code::kIo, "cannot write '" + tmp + "' (disk full?)");
  }
  return Ok{};
}

}  // namespace

namespace detail {
sigset_t EndingSignalSet() {
  sigset_t set;
  sigemptyset(&set);
  for (const int sig : kEndingSignals) sigaddset(&set, sig);
  return set;
}

struct LiveTemporary {
  std::string path;
  LiveTemporary* prev = nullptr;
  LiveTemporary* next = nullptr;
};
}  // namespace detail

namespace {

// Every OutputFiles temporary of the process not yet renamed or removed, newest first, for
// RemoveTemporariesOnSignal. A thread changes the list with the ending signals blocked (so a handler never runs in
// the thread that holds the lock) and under a spin lock, which the handler takes for good: the process is ending.
// Nothing under the lock allocates (the nodes are made and freed outside it), so a handler that interrupted malloc
// in another thread cannot wait on a holder that waits on malloc.
std::atomic<int> g_live_lock{0};  // 0 free, 1 held by a change, 2 taken by the handler
detail::LiveTemporary* g_live_head = nullptr;

// The ending signals blocked in this thread for the object's life (nests: each restores what it found).
class BlockEndingSignals {
 public:
  BlockEndingSignals() {
    const sigset_t ending = detail::EndingSignalSet();
    ::pthread_sigmask(SIG_BLOCK, &ending, &old_);
  }
  ~BlockEndingSignals() { ::pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  BlockEndingSignals(const BlockEndingSignals&) = delete;
  BlockEndingSignals& operator=(const BlockEndingSignals&) = delete;

 private:
  sigset_t old_;
};

class LiveLock {
 public:
  LiveLock() {
    for (int free = 0; !g_live_lock.compare_exchange_weak(free, 1, std::memory_order_acquire); free = 0) {
    }
  }
  ~LiveLock() { g_live_lock.store(0, std::memory_order_release); }
  LiveLock(const LiveLock&) = delete;
  LiveLock& operator=(const LiveLock&) = delete;

 private:
  BlockEndingSignals blocked_;  // first in, last out
};

// Links `node` at the head of the list. With `create`, also creates its file (new, mode 0666 less the umask)
// before the lock is released, so that no handler can run between the two and miss it: the file
// descriptor, or -1 with errno set.
int Track(detail::LiveTemporary* node, bool create) {
  int fd = -1, error = 0;
  {
    LiveLock lock;
    node->next = g_live_head;
    if (g_live_head) g_live_head->prev = node;
    g_live_head = node;
    // A new file of its own (O_EXCL | O_NOFOLLOW): a file or link found at the (predictable) name is never
    // written through. It is removed (unlink takes the link, not what it points to) and the file made once more:
    // a leftover of a killed process that had the same id, or a link planted in a shared folder.
    const int flags = O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC;
    if (create) {
      fd = ::open(node->path.c_str(), flags, 0666);
      if (fd < 0 && errno == EEXIST && ::unlink(node->path.c_str()) == 0) fd = ::open(node->path.c_str(), flags, 0666);
      error = errno;
    }
  }
  errno = error;  // as open left it, whatever the unlock did
  return fd;
}

// Unlinks the nodes of `files` from the list, the lock already held (frees nothing).
template <typename It>
void UnlinkLocked(It first, It last) {
  for (It it = first; it != last; ++it) {
    detail::LiveTemporary* n = it->live;
    (n->prev ? n->prev->next : g_live_head) = n->next;
    if (n->next) n->next->prev = n->prev;
  }
}

// Unlinks them under one lock (whatever their number: a folder of frames stages thousands), then frees them.
template <typename It>
void Untrack(It first, It last) {
  if (first == last) return;
  {
    LiveLock lock;
    UnlinkLocked(first, last);
  }
  for (It it = first; it != last; ++it) delete it->live;
}
}  // namespace

void RemoveTemporariesOnSignal() noexcept {
  for (int free = 0; !g_live_lock.compare_exchange_weak(free, 2, std::memory_order_acquire); free = 0) {
  }
  // Newest first: a writer's own temporary (a glTF's, renamed onto a staged path) goes before the staged path,
  // so that another thread's rename cannot bring the staged one back afterwards.
  for (const detail::LiveTemporary* n = g_live_head; n; n = n->next) ::unlink(n->path.c_str());  // async-signal-safe
}

Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size) {
  OutputFiles one;  // a set of one file: written to its temporary, then renamed
  if (auto s = one.Write(path, bytes, size); !s.ok()) return s;
  return one.Commit();
}

OutputFiles::~OutputFiles() {
  std::error_code ec;
  for (const File& f : files_) std::filesystem::remove(f.temporary, ec);  // none left once committed
  Untrack(files_.begin(), files_.end());
}

OutputFiles::File& OutputFiles::Add(const std::string& path, const std::string& suffix) {
  auto node = std::make_unique<detail::LiveTemporary>();
  node->path = TemporaryPathFor(path, suffix);
  files_.push_back({node->path, path, node.get()});
  node.release();  // files_ owns it now: freed by Untrack
  return files_.back();
}

std::string OutputFiles::Stage(const std::string& path, const std::string& suffix) {
  File& f = Add(path, suffix);
  Track(f.live, /*create=*/false);  // before the writer can make the file
  return f.temporary;
}

Status OutputFiles::Write(const std::string& path, const void* bytes, size_t size) {
  if (auto s = OutputFolderExists(path); !s.ok()) return s;
  File& f = Add(path, {});
  const int fd = Track(f.live, /*create=*/true);
  if (fd < 0) return Explain(MakeError(Error::Code::kIo, "cannot create '" + f.temporary + "': " + std::strerror(errno)));
  if (auto s = WriteWhole(fd, f.temporary, bytes, size); !s.ok()) return Explain(s.error());
  return Ok{};
}

Error OutputFiles::Explain(Error error) const {
  std::string& m = error.message;
  for (const File& f : files_) {
    const std::string &tmp = f.temporary, &path = f.path;
    // A writer's own temporary of the staged one (TemporaryPathFor(tmp, suffix): DIR/.NAME.tmpPID.N[suffix]) up
    // to the end of its name, then the staged temporary itself.
    const std::filesystem::path t(tmp);
    const std::string nested = (t.parent_path() / ("." + t.filename().string() + ".tmp")).string();
    for (size_t at = m.find(nested); at != std::string::npos; at = m.find(nested, at + path.size())) {
      size_t end = at + nested.size();
      while (end < m.size() && (std::isalnum(static_cast<unsigned char>(m[end])) || m[end] == '.')) ++end;
      m.replace(at, end - at, path);
    }
    for (size_t at = m.find(tmp); at != std::string::npos; at = m.find(tmp, at + path.size())) m.replace(at, tmp.size(), path);
  }
  return error;
}

Status OutputFiles::Commit() {
  // The set is renamed whole, or, interrupted before, not at all. No ending signal reaches this thread between
  // two renames, and the list's lock is held across them: a handler that another thread runs meanwhile (a
  // signal sent to the process goes to any thread that does not block it, a TBB worker say) waits for the last
  // rename, then removes only what was not renamed. Under the lock nothing allocates: system calls on the
  // paths' own bytes, the messages made after.
  size_t done = 0;  // files_[0, done) are in place, or were never made (a writer that wrote nothing)
  int error = 0;
  const char* what = nullptr;
  {
    LiveLock lock;
    for (; done < files_.size(); ++done) {
      const char *tmp = files_[done].temporary.c_str(), *path = files_[done].path.c_str();
      struct stat st;
      if (::lstat(tmp, &st) != 0) {
        if (errno == ENOENT) continue;  // staged for a writer that wrote nothing: the path stays as it was
        error = errno, what = "cannot read the temporary file of '";
        break;
      }
      if (::rename(tmp, path) != 0) {
        error = errno, what = "cannot rename the temporary file onto '";
        break;
      }
    }
    UnlinkLocked(files_.begin(), files_.begin() + static_cast<std::ptrdiff_t>(done));
  }
  // The first `done` files: forgotten, nothing left to remove.
  const auto end = files_.begin() + static_cast<std::ptrdiff_t>(done);
  for (auto it = files_.begin(); it != end; ++it) delete it->live;
  const std::string failed = what ? files_[done].path : std::string();
  files_.erase(files_.begin(), end);
  if (what) return MakeError(Error::Code::kIo, what + failed + "': " + std::strerror(error));
  return Ok{};
}

std::string TemporaryPathFor(const std::string& path, const std::string& suffix) {
  namespace fs = std::filesystem;
  // The process and a count of its temporary files: two threads writing one path at once (Python releases
  // the GIL) each write a file of their own, and the last rename wins whole.
  static std::atomic<uint64_t> count{0};
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  return (dir / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()) + "." +
                 std::to_string(count.fetch_add(1)) + suffix))
      .string();
}

Result<std::string> MakeDepfile(const std::string& target, const std::vector<std::string>& prerequisites) {
  std::string text;
  // gcc's mkdeps.c quoting, which GNU make and Ninja's depfile parser read back.
  auto append = [&text](const std::string& path) -> Status {
    if (path.empty()) return MakeError(Error::Code::kIo, "depfile: an empty path cannot be a dependency");
    for (size_t i = 0; i < path.size(); ++i) {
      const char c = path[i];
      if (c == '\n' || c == '\r')
        return MakeError(Error::Code::kIo, "depfile: '" + path + "' holds a line break, which a depfile cannot name");
      if (c == ' ' || c == '\t') {
        for (size_t k = i; k > 0 && path[k - 1] == '\\'; --k) text += '\\';  // 2N+1 backslashes: N, then the blank
        text += '\\';
      } else if (c == '#') {
        text += '\\';
      } else if (c == '$') {
        text += '$';
      }
      text += c;
    }
    return Ok{};
  };
  if (Status s = append(target); !s.ok()) return s.error();
  text += ':';
  for (const std::string& p : prerequisites) {
    text += " \\\n ";
    if (Status s = append(p); !s.ok()) return s.error();
  }
  text += '\n';
  for (const std::string& p : prerequisites) {
    text += '\n';
    if (Status s = append(p); !s.ok()) return s.error();
    text += ":\n";
  }
  return text;
}

Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path, size_t max_size) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) return MakeError(Error::Code::kIo, "'" + path + "': no such file");
  if (fs::is_directory(path, ec)) return MakeError(Error::Code::kIo, "'" + path + "' is a folder, not a file");
  const auto size = fs::file_size(path, ec);
  if (ec) return MakeError(Error::Code::kIo, "'" + path + "': " + ec.message());
  if (size > max_size)
    return MakeError(Error::Code::kIo, "'" + path + "' is " + std::to_string(size) + " bytes, over the limit of " +
                                           std::to_string(max_size));
  std::ifstream in(path, std::ios::binary);
  if (!in) return MakeError(Error::Code::kIo, "'" + path + "': cannot open for reading");
  std::vector<uint8_t> bytes(size);
  if (size && !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
    return MakeError(Error::Code::kIo, "'" + path + "': read failed");
  return bytes;
}

Status LoadAssetBytes(const uint8_t* bytes, size_t size, const std::string& name, LoadedAsset* out) {
  out->size = size;
  out->storage.reset(new uint64_t[(size + 7) / 8 + 1]);
  if (size) std::memcpy(out->storage.get(), bytes, size);
  const runtime::Status s = out->status = runtime::LoadAsset(out->bytes(), out->size, &out->view);
  if (runtime::Failed(s))
    return MakeError(Error::Code::kFormat, name + " is not a loadable .sphc asset: " + runtime::ToString(s));
  return Ok{};
}

Status LoadAssetFile(const std::string& path, LoadedAsset* out) {
  auto bytes = ReadFileBytes(path, runtime::kMaxAssetBytes);
  if (!bytes.ok()) return bytes.error();
  return LoadAssetBytes(bytes->data(), bytes->size(), "'" + path + "'", out);
}

namespace {
// `p` absolute with `.`, `..` and symbolic links of its existing part resolved; lexically when that fails.
std::filesystem::path Resolved(const std::string& p) {
  std::error_code ec;
  std::filesystem::path r = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec);
  return ec ? std::filesystem::path(p).lexically_normal() : r;
}
}  // namespace

std::string OutputPathProblem(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
    return "cannot write '" + path + "': folder '" + dir.string() + "' does not exist";
  if (std::filesystem::is_directory(path, ec)) return "cannot write '" + path + "': it is a folder";
  return {};
}

std::string OutputsClash(const std::vector<PathArg>& outputs, const std::vector<PathArg>& inputs,
                         const std::vector<std::string>& more_inputs) {
  std::vector<std::pair<const char*, std::filesystem::path>> written;
  for (const PathArg& out : outputs) {
    if (out.path->empty()) continue;
    const std::filesystem::path r = Resolved(*out.path);
    for (const auto& [name, other] : written)
      if (other == r)
        return std::string(name) + " and " + out.name + " both name '" + *out.path + "': one would overwrite the other";
    auto is = [&](const std::string& in) { return !in.empty() && Resolved(in) == r; };
    auto clash = [&](const char* name) {
      return std::string(out.name) + " '" + *out.path + "' is also " + name + ": writing it would destroy what is read";
    };
    for (const PathArg& in : inputs)
      if (is(*in.path)) return clash(in.name);
    for (const std::string& in : more_inputs)
      if (is(in)) return clash("an input");
    written.emplace_back(out.name, r);
  }
  return {};
}

}  // namespace spherechain::import
