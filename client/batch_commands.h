#pragma once
// Running an equal-time batch (core/batch/batch_spec.h) from the client: on a coordinator, or on
// an embedded farm in this process. Used by `penumbra batch run` and `penumbra demo`.

#include <filesystem>
#include <string>

namespace penumbra {

// A bundled scene's file: $PENUMBRA_SCENES/<name>.json, else the source tree's scenes/.
std::string bundled_scene_path(const std::string& name);
// A bundled batch's file: $PENUMBRA_BATCHES/<name>.json, else the source tree's batches/.
std::string bundled_batch_path(const std::string& name);

struct BatchRunSettings {
  std::string coordinator;                       // empty: an embedded farm
  std::string tls_ca, tls_cert, tls_key, token;  // for a coordinator (farm_client.h)
  int workers = 0;                               // embedded farm: worker count (0: one per core)
  int threads_per_worker = 1;                    // embedded farm
  bool print_table = true;                       // the summary table on stdout
  bool write_report = true;                      // write_batch_report into the output folder
  bool quiet = false;                            // no progress while the batch runs
};

// Submits the spec (text, with `source_name` and `base_dir` for its relative paths), watches it
// with a progress line, writes the batch result folder into `out_dir` and the report beside it.
// Returns the batch id. Throws on failure.
std::string run_batch(const std::string& spec_text, const std::string& source_name,
                      const std::string& base_dir, const std::filesystem::path& out_dir,
                      const BatchRunSettings& settings);

}  // namespace penumbra
