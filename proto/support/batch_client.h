#pragma once
// The client side of the coordinator's Batches service (penumbra.v1.Batches): what `penumbra
// batch ...`, the demo and the tests use. Failed calls throw FarmCallError (farm_client.h).
//
// Also the batch result folder (/work/briefs/s2_batch_contract.md, batches/README.md) that
// `penumbra batch fetch/run` write and core/report reads:
//   DIR/batch.json, DIR/reference.exr, DIR/runs/<label>.r<repeat>.exr (equal-time runs) and
//   DIR/runs/<label>.spp<N>.r<repeat>.exr (spp levels); errors computed with core/image/metrics.h
//   from exactly those EXRs.

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/v1/farm.grpc.pb.h"
#include "proto/support/farm_client.h"

namespace penumbra::farm {

class BatchClient {
 public:
  explicit BatchClient(const std::string& address);
  explicit BatchClient(const FarmConnection& connection);

  v1::SubmitBatchResponse submit(const v1::SubmitBatchRequest& request);
  // The request's scene package uploaded in chunks first (upload_scene, farm_client.h; its
  // content hash is `scene_hash`), then the request submitted naming it by hash: no message
  // carries the whole scene.
  v1::SubmitBatchResponse upload_and_submit(v1::SubmitBatchRequest request,
                                            const std::string& scene_hash);
  v1::BatchStatus status(const std::string& batch_id);  // with the runs' curves
  std::vector<v1::BatchStatus> list();
  v1::BatchStatus cancel(const std::string& batch_id);
  std::string fetch_reference(const std::string& batch_id);  // EXR bytes
  std::string fetch_result(const std::string& job_id);       // a run's EXR bytes
  // Streams status events to `on_event` until the batch ends; returns the final status (with
  // curves). Reconnects while the coordinator is away, up to `timeout` in all.
  v1::BatchStatus watch(const std::string& batch_id,
                        const std::function<void(const v1::BatchStatus&)>& on_event,
                        std::chrono::milliseconds timeout = std::chrono::hours(24 * 365));

 private:
  std::string address_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Batches::Stub> stub_;
  std::unique_ptr<v1::Jobs::Stub> jobs_;
};

bool is_terminal(v1::BatchState state);

// Reads a batch spec file and builds the request: the spec's text, its scene packed (a bundled
// name is resolved by `bundled_scene_path`, anything with a '/' or ending in ".json" is a path
// relative to the spec's folder, or else to the working directory) and, for an EXR reference,
// the file's bytes. Throws FormatError (bad spec, unreadable scene or EXR) naming the path.
v1::SubmitBatchRequest make_batch_request(
    const std::string& spec_path,
    const std::function<std::string(const std::string&)>& bundled_scene_path);
// The same from spec text already in memory (`source_name` for messages, `base_dir` for paths).
v1::SubmitBatchRequest make_batch_request_from_text(
    const std::string& spec_text, const std::string& source_name, const std::string& base_dir,
    const std::function<std::string(const std::string&)>& bundled_scene_path);

// Writes the batch result folder for a batch that has ended (fetching the reference and every
// finished run's EXR). Throws FarmCallError / std::runtime_error.
void write_batch_result(BatchClient& client, const v1::BatchStatus& status,
                        const std::filesystem::path& dir);

}  // namespace penumbra::farm
