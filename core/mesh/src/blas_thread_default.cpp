// OpenBLAS on one thread in texwarp's executables unless the user chose its thread count (linked into `texwarp` and
// `texwarpd` only, as the OBJECT library texwarp_blas_thread_default; the Python module leaves its host's BLAS alone).
//
// CHOLMOD's supernodal factor (the mesh solvers: LSCM, the UV optimisation) runs on OpenBLAS, whose pthread build
// starts a pool of (cores − 1) threads in its constructor, at every process start, and lets them spin (sched_yield)
// for about 0.1 s, then again after every BLAS call it splits among them. On the 2-core machine (the user guide's
// map-mesh section has the figures) the pool cost a 50-feature warp, which never calls BLAS, 18 % more CPU at the same
// wall time, and a 180 000-face mesh job 53 % more CPU for 4 % less wall time; texwarpd runs jobs side by side, where
// those CPU-seconds are other jobs'. OpenBLAS reads its thread count from the environment in that constructor, and
// setting the variable earlier does not work (glibc's own initialiser, which runs after an executable's
// .preinit_array, resets the environment to the one the process started with). So once every library is
// initialised, this executable's constructor sets the count to one and stops the pool, unless one of the variables
// OpenBLAS reads (OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS, OMP_NUM_THREADS) is set. Both functions are looked up, not
// linked: another BLAS under CHOLMOD (the reference BLAS, BLIS) has neither and is left as it is.
#include <dlfcn.h>

#include <cstdlib>
#include <initializer_list>

namespace {

// Runs after every shared library's constructors (OpenBLAS's included), before main.
__attribute__((constructor)) void one_blas_thread_unless_chosen() {
  for (const char* chosen : {"OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS"}) {
    if (std::getenv(chosen) != nullptr) return;
  }
  // OpenBLAS's public setter, then its pool's shutdown (what it runs itself before a fork); a later BLAS call on one
  // thread never starts the pool again.
  using SetThreads = void (*)(int);
  using Shutdown = int (*)();
  if (void* set = ::dlsym(RTLD_DEFAULT, "openblas_set_num_threads")) {
    reinterpret_cast<SetThreads>(set)(1);
    if (void* shutdown = ::dlsym(RTLD_DEFAULT, "blas_thread_shutdown_")) reinterpret_cast<Shutdown>(shutdown)();
  }
}

}  // namespace
