/* The C API out of memory, in the library as installed: sc_model_create with the narrow phase (the largest
 * allocations of a model) in a child process whose address space is capped a little above what it already
 * uses, for caps from 16 KiB up, doubling until it succeeds. Every capped call must return
 * SC_ERROR_OUT_OF_MEMORY (or SC_OK once the cap is enough), never abort: the library keeps its contract
 * even when the runtime beside it is built without exceptions. Linux (RLIMIT_AS, /proc/self/statm).
 * Usage: oom_c ASSET.sphc (an asset with the crease rule). Exit 0 when it held, 1 with the reason. */
#define _GNU_SOURCE
#include <spherechain/spherechain.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

static long address_space_bytes(void) {
  long pages = 0;
  FILE* f = fopen("/proc/self/statm", "r");
  if (!f || fscanf(f, "%ld", &pages) != 1) pages = 0;
  if (f) fclose(f);
  return pages * sysconf(_SC_PAGESIZE);
}

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: oom_c ASSET.sphc\n");
    return 1;
  }
  FILE* f = fopen(argv[1], "rb");
  if (!f) {
    fprintf(stderr, "cannot open %s\n", argv[1]);
    return 1;
  }
  fseek(f, 0, SEEK_END);
  const long size = ftell(f);
  fseek(f, 0, SEEK_SET);
  void* bytes = aligned_alloc(16, (size_t)(size + 15) / 16 * 16);
  if (!bytes || fread(bytes, 1, (size_t)size, f) != (size_t)size) {
    fprintf(stderr, "cannot read %s\n", argv[1]);
    return 1;
  }
  fclose(f);
  int out_of_memory = 0;
  for (long extra = 16L << 10; extra <= 1L << 30; extra *= 2) {
    fflush(stdout);
    const pid_t pid = fork();
    if (pid == 0) {
      struct rlimit cap;
      cap.rlim_cur = cap.rlim_max = (rlim_t)(address_space_bytes() + extra);
      setrlimit(RLIMIT_AS, &cap);
      sc_model* model = NULL;
      const sc_status s = sc_model_create(bytes, (size_t)size, SC_MODEL_NARROW_PHASE, &model);
      _exit(s == SC_OK ? 0 : s == SC_ERROR_OUT_OF_MEMORY ? 2 : 3);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFSIGNALED(status)) {
      printf("oom: +%ld KiB: the child died of signal %d (%s): an allocation failure was not returned\n", extra >> 10,
             WTERMSIG(status), strsignal(WTERMSIG(status)));
      return 1;
    }
    const int code = WEXITSTATUS(status);
    if (code == 3) {
      printf("oom: +%ld KiB: sc_model_create returned neither SC_OK nor SC_ERROR_OUT_OF_MEMORY\n", extra >> 10);
      return 1;
    }
    if (code == 2) ++out_of_memory;
    if (code == 0) {
      printf("oom: SC_ERROR_OUT_OF_MEMORY under %d caps, SC_OK at +%ld KiB\n", out_of_memory, extra >> 10);
      return out_of_memory > 0 ? 0 : (printf("oom: no cap made an allocation fail\n"), 1);
    }
  }
  printf("oom: no cap up to 1 GiB was enough\n");
  return 1;
}
