// The batch commands' function options (batch_function_options.hpp).
#include "options/batch_function_options.hpp"

#include "options/cache_location.hpp"

namespace robodiff::cli {

void addBatchFunctionOptions(CLI::App& cmd, BatchFunctionArgs& args, const std::string& what, bool with_threads) {
  cmd.add_option("--backend", args.backend,
                 "compiled (default): the compiled library from the cache, built first when missing (batched entry "
                 "point); interpreted: no compiler, ready at once, slower per " + what)
      ->check(CLI::IsMember({"compiled", "generated", "interpreted"}))
      ->type_name("compiled|interpreted");
  cmd.add_option("--cache", args.cache_dir,
                 "Cache directory for compiled functions (default: $ROBODIFF_CACHE_DIR, else "
                 "$XDG_CACHE_HOME/robodiff, else ~/.cache/robodiff)")
      ->type_name("DIR");
  cmd.add_option("--compiler", args.compiler, "C compiler to run when building (default: $CC, else cc)")
      ->type_name("CC");
  if (with_threads)
    cmd.add_option("--threads", args.threads, "Threads evaluating " + what + " (default: all cores)")
        ->check(CLI::Range(1u, 4096u))
        ->type_name("N");
}

batch::BatchFunctionOptions batchFunctionOptions(const BatchFunctionArgs& args) {
  batch::BatchFunctionOptions options;
  options.backend = batch::parseBackend(args.backend);
  options.threads = args.threads;
  options.compiler = args.compiler;
  if (options.backend == batch::Backend::Compiled) options.cache_dir = cacheDirFor(args.cache_dir);
  return options;
}

}  // namespace robodiff::cli
