// spherechain import — files and identities: whole-file reads with a size cap, atomic writes (nothing
// half-written on failure), the mesh fingerprint an asset records (schema Fingerprint), weld ids
// (schema Asset.weld_ids), XXH3-64 hashes, and a .sphc read into aligned memory and verified.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "spherechain/import/types.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::import {

/// Source fingerprint (schema Fingerprint): counts and XXH3-64 of the bind positions (\#V×3 float32)
/// and indices (\#T×3 uint32) as read.
struct Fingerprint {
  uint32_t vertex_count = 0;
  uint32_t triangle_count = 0;
  uint64_t positions_hash = 0;
  uint64_t indices_hash = 0;
};
Fingerprint ComputeFingerprint(const Mesh& mesh);

/// Weld ids (schema Asset.weld_ids) of bind positions `positions` (\#V×3): for every vertex the lowest
/// vertex index whose position compares equal (==, so +0 and −0 weld) — UV seams and triangle soups
/// get the adjacency a narrow phase needs to skip triangles that share a corner. Nothing is merged:
/// the index buffer keeps the source's vertices. Cost O(\#V log \#V), deterministic.
std::vector<uint32_t> ComputeWeldIds(const std::vector<float>& positions);

/// XXH3-64 of arbitrary bytes (the canonical bake configuration, ...).
uint64_t Hash64(const void* data, size_t size);

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed, then renamed over
/// `path`. On any failure the temporary is removed and `path` is untouched. Errors: kIo.
Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size);
/// A hidden temporary name beside `path` that no other write of this process or another uses
/// (".NAME.tmpPID.N" + `suffix`, in path's folder): what WriteFileAtomic writes before its rename.
std::string TemporaryPathFor(const std::string& path, const std::string& suffix = {});
inline Status WriteFileAtomic(const std::string& path, const std::string& text) {
  return WriteFileAtomic(path, text.data(), text.size());
}

namespace detail {
struct LiveTemporary;
}  // namespace detail

/// A command's output files written all or nothing (an asset with its report and pictures, a folder of
/// frames): each is first written whole to a hidden temporary beside its path (TemporaryPathFor), and
/// Commit() renames them onto their paths, in the order they were staged, once every one is written. Until
/// then every path keeps what it held (an earlier run's file stays as it was); the destructor removes the
/// temporaries not committed. Not thread-safe; one set per command.
class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  ~OutputFiles();
  /// Writes `bytes` whole to `path`'s temporary (flushed to the disk). Errors: kIo when path's folder does not
  /// exist or the temporary cannot be created or written (it is removed).
  Status Write(const std::string& path, const void* bytes, size_t size);
  Status Write(const std::string& path, const std::string& text) { return Write(path, text.data(), text.size()); }
  /// A temporary path for `path` (TemporaryPathFor(path, suffix)) that a writer of its own fills: a PNG by
  /// rsvg-convert, a glTF by its exporter. Commit() renames it onto `path` when the writer made it, and skips it
  /// (the path unchanged) when it did not. Reads and writes nothing.
  std::string Stage(const std::string& path, const std::string& suffix = {});
  /// Renames every staged temporary onto its path. Errors: kIo when a temporary cannot be looked at or a rename
  /// fails: the files before it are in place, the rest keep what they held (their temporaries removed). A
  /// rename within one folder needs no space, so this is a folder changed under the command (or a file there
  /// the user may not replace), not a full disk. Call once.
  Status Commit();
  /// `error` with every staged temporary's name, and a writer's own temporary of it, replaced by the path it
  /// stands for: what a message of a writer given Stage()'s path tells the user. Allocates.
  Error Explain(Error error) const;

 private:
  struct File {
    std::string temporary, path;
    detail::LiveTemporary* live;  // its entry in the process's list of temporaries (RemoveTemporariesOnSignal)
  };
  File& Add(const std::string& path, const std::string& suffix);
  std::vector<File> files_;  // in staging order
};

/// Removes the temporaries of every OutputFiles of the process that are neither committed nor removed yet
/// (those staged, written or being written; a file a writer of its own has not made yet is skipped): what a
/// command's handler of SIGINT, SIGTERM, SIGHUP or SIGQUIT calls before the process ends, so that an interrupted
/// command leaves no hidden file behind and every path keeps what it held. Async-signal-safe (unlink(2) over the
/// process's list, which its changes make with those four signals blocked). A one-way door: afterwards any
/// OutputFiles use in the process waits forever, so call it only on the way out (then re-raise the signal).
void RemoveTemporariesOnSignal() noexcept;

/// Why output file `path` cannot be written, found before the work that would write it: "cannot write 'p':
/// folder 'd' does not exist" or "cannot write 'p': it is a folder"; empty when it can be tried (the write
/// may still fail). Two stats; reads no file.
std::string OutputPathProblem(const std::string& path);

/// One file a command reads or writes: how its users name it ("-o", "--report", "ASSET"; in Python the
/// argument's name) and its path (empty: not given). Both pointers must outlive the call.
struct PathArg {
  const char* name;
  const std::string* path;
};
/// Whether writing the outputs would destroy a file the command reads or another output. The message says
/// which: two outputs "both name 'x': one would overwrite the other"; an output "is also" an input (those of
/// `more_inputs` are called an input) "writing it would destroy what is read". Two paths are one file when
/// they are equal after resolving dot segments and symbolic links of their existing part (lexically when that
/// fails). Empty when all are distinct. Reads no file; a few stats per path.
std::string OutputsClash(const std::vector<PathArg>& outputs, const std::vector<PathArg>& inputs,
                         const std::vector<std::string>& more_inputs = {});

/// A dependency file in Makefile syntax ("depfile", what `gcc -MD -MP` writes), read by Make, Ninja and CMake
/// (add_custom_command DEPFILE): the rule `target: prerequisites...`, then an empty rule per prerequisite so
/// that Make does not stop when one is deleted. Every path is escaped as Make reads it: a space or tab as
/// `\ ` (the backslashes before it doubled), `#` as `\#`, `$` as `$$`. `target` is written as given (the
/// output path as the build system named it); `prerequisites` in order (Context::files_read: absolute).
/// Errors: kIo when a path holds a line break (no depfile can name it) or is empty. Allocates.
Result<std::string> MakeDepfile(const std::string& target, const std::vector<std::string>& prerequisites);

/// Reads a whole file. Errors: kIo. `max_size` caps what is read (kIo "file too large").
Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path, size_t max_size = size_t(1) << 31);

/// A .sphc asset in memory: the file's bytes, 8-byte aligned as runtime::LoadAsset requires, and the
/// verified view into them. Owns the bytes; the view points into them (stable when the struct moves).
struct LoadedAsset {
  std::unique_ptr<uint64_t[]> storage;
  size_t size = 0;  ///< bytes of the file
  runtime::AssetView view;
  runtime::Status status = runtime::Status::kOk;  ///< what runtime::LoadAsset said (the reason when it failed)
  const uint8_t* bytes() const { return reinterpret_cast<const uint8_t*>(storage.get()); }
};

/// Copies `size` bytes into aligned storage owned by `out` and verifies them (runtime::LoadAsset).
/// Errors: kFormat "<name> is not a loadable .sphc asset: <runtime status>" (`name` says where the
/// bytes came from, for the message). Cost: one copy and the FlatBuffers verifier, O(size).
Status LoadAssetBytes(const uint8_t* bytes, size_t size, const std::string& name, LoadedAsset* out);

/// Reads `path` (at most runtime::kMaxAssetBytes) and loads it as LoadAssetBytes does. Errors: kIo
/// (missing, a folder, too large, unreadable), kFormat (not a loadable asset). The one way the offline
/// tools read an asset file.
Status LoadAssetFile(const std::string& path, LoadedAsset* out);

}  // namespace spherechain::import
