// spherechain bake A B ... --out-dir DIR [-j N]: independent bakes on worker threads, a progress bar, a
// summary table.
#include "bake_batch.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>
#include <utility>

#include <spdlog/spdlog.h>

#include "commands.h"
#include "spherechain/import/file_io.h"

namespace spherechain::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// One input of the batch and what became of it.
struct Item {
  std::string input;   // as given
  std::string name;    // its file name (unique in a batch: two inputs with one stem are refused)
  std::string output;  // DIR/<stem>.sphc
  bool ok = false;
  size_t spheres = 0, bytes = 0;
  double seconds = 0.0;
  std::string error;  // "<kind>: <message>" when it failed
  std::vector<std::pair<import::Context::Level, std::string>> log;
};

/// Bakes one item and writes its asset; everything it says goes into the item (printed by the caller).
void BakeOne(const baker::BakeConfig& config, Item* item) {
  const auto t0 = Clock::now();
  import::Context ctx;
  ctx.sink = [item](import::Context::Level level, const std::string& m) { item->log.emplace_back(level, m); };
  auto fail = [item](const import::Error& e) { item->error = import::ToString(e); };
  try {  // an exception must not end the other inputs' bakes (the baker returns errors; this is the last net)
    auto result = baker::Bake(item->input, config, &ctx);
    if (!result.ok()) {
      fail(result.error());
    } else if (auto s = import::WriteFileAtomic(item->output, result->asset.data(), result->asset.size()); !s.ok()) {
      fail(s.error());
    } else {
      item->ok = true;
      item->spheres = result->fit.spheres.size();
      item->bytes = result->asset.size();
    }
  } catch (const std::exception& e) {
    fail(import::MakeError(import::Error::Code::kInternal, item->input + ": " + e.what()));
  }
  item->seconds = std::chrono::duration<double>(Clock::now() - t0).count();
}

/// The progress shown on stderr: a bar redrawn in place on a terminal, one line per finished input otherwise.
class Progress {
 public:
  Progress(size_t total, bool bar) : total_(total), bar_(bar) {}
  /// Before other output on stderr: the bar's line cleared.
  void Clear() {
    if (bar_ && drawn_) std::fprintf(stderr, "\r\033[2K");
    drawn_ = false;
  }
  void Finished(const Item& item, size_t done) {
    if (bar_) {
      const int width = 30, filled = int(width * double(done) / double(total_));
      std::fprintf(stderr, "\r\033[2Kbake [%-*s] %zu/%zu  %s %s", width, std::string(size_t(filled), '#').c_str(), done,
                   total_, item.name.c_str(), item.ok ? "ok" : "FAILED");
      drawn_ = true;
      if (done == total_) std::fprintf(stderr, "\n"), drawn_ = false;
    } else {
      std::fprintf(stderr, "bake: %zu/%zu %s %s (%.2f s)\n", done, total_, item.ok ? "ok" : "FAILED",
                   item.name.c_str(), item.seconds);
    }
    std::fflush(stderr);
  }

 private:
  size_t total_;
  bool bar_, drawn_ = false;
};

void PrintTable(const std::vector<Item>& items, unsigned jobs, double wall) {
  size_t w = 5, failed = 0;
  for (const Item& it : items) w = std::max(w, it.name.size()), failed += !it.ok;
  Out("\n%-*s  %-6s  %7s  %10s  %7s  %s\n", int(w), "input", "result", "spheres", "bytes", "seconds", "asset or error");
  for (const Item& it : items) {
    if (it.ok)
      Out("%-*s  %-6s  %7zu  %10zu  %7.2f  %s\n", int(w), it.name.c_str(), "ok", it.spheres, it.bytes, it.seconds,
          it.output.c_str());
    else
      Out("%-*s  %-6s  %7s  %10s  %7.2f  %s\n", int(w), it.name.c_str(), "FAILED", "-", "-", it.seconds,
          it.error.c_str());
  }
  Out("%zu of %zu baked, %zu failed, in %.2f s (-j %u)\n", items.size() - failed, items.size(), failed, wall, jobs);
}

}  // namespace

int RunBatchBake(const std::vector<std::string>& inputs, const std::string& out_dir, unsigned jobs,
                 const baker::BakeConfig& config) {
  // Plan every output before any bake: one output per input, no two inputs on one output.
  std::vector<Item> items(inputs.size());
  std::map<std::string, size_t> by_output;
  for (size_t i = 0; i < inputs.size(); ++i) {
    Item& it = items[i];
    it.input = inputs[i];
    it.name = fs::path(inputs[i]).filename().string();
    it.output = (fs::path(out_dir) / fs::path(inputs[i]).stem()).string() + ".sphc";
    auto [at, fresh] = by_output.emplace(it.output, i);
    if (!fresh) {
      Fail("'" + inputs[at->second] + "' and '" + inputs[i] + "' would both be baked into '" + it.output +
           "' (one asset per file stem): bake them into different --out-dir folders");
      return 2;
    }
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (!fs::is_directory(out_dir, ec)) return Fail("cannot create the output folder '" + out_dir + "'");

  if (jobs == 0) jobs = std::max(1u, std::thread::hardware_concurrency());
  jobs = unsigned(std::min<size_t>(jobs, items.size()));
  const auto t0 = Clock::now();
  Progress progress(items.size(), isatty(2) && !Quiet());
  std::mutex print;  // stderr and stdout: one finished input at a time
  std::atomic<size_t> next{0};
  size_t done = 0;
  auto worker = [&] {
    for (size_t i; (i = next.fetch_add(1)) < items.size();) {
      Item& it = items[i];
      BakeOne(config, &it);
      std::lock_guard<std::mutex> lock(print);
      ++done;
      progress.Clear();
      for (const auto& [level, m] : it.log) {
        if (level == import::Context::Level::kWarn) spdlog::warn("{}: {}", it.name, m);
        else spdlog::debug("{}: {}", it.name, m);  // a batch's info lines: with -v
      }
      if (!it.ok) spdlog::error("{}: {}", it.name, it.error);
      if (!Quiet()) progress.Finished(it, done);
    }
  };
  std::vector<std::thread> threads;
  for (unsigned k = 1; k < jobs; ++k) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  PrintTable(items, jobs, std::chrono::duration<double>(Clock::now() - t0).count());
  return std::all_of(items.begin(), items.end(), [](const Item& it) { return it.ok; }) ? 0 : 1;
}

}  // namespace spherechain::cli
