#pragma once
// A whole farm in one process: a coordinator on a loopback port and N workers on threads. It is
// what `penumbra demo` runs: no setup beyond the build. Jobs go through the same gRPC API as on
// a real farm, so the demo exercises the farm end to end.
//
//   EmbeddedFarm farm({.workers = 2, .threads_per_worker = 1});
//   v1::JobSpec spec;  // spec.mutable_scene() = pack_scene_file(path); method, sampler, spp...
//   Film film = farm.run(spec, [](const v1::JobStatus& s) { ... progress ... });

#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/render/film.h"
#include "penumbra/v1/farm.pb.h"
#include "proto/support/farm_client.h"
#include "server/coordinator.h"
#include "server/coordinator_server.h"
#include "worker/worker.h"

namespace penumbra::farm {

struct EmbeddedFarmOptions {
  int workers = 2;
  int threads_per_worker = 1;
  // The coordinator's state; empty: a fresh temporary folder, removed when the farm stops.
  std::string data_dir;
  std::chrono::milliseconds lease_time{10'000};
  size_t max_scene_bytes = size_t(256) << 20;  // the coordinator's scene-size limit
};

class EmbeddedFarm {
 public:
  explicit EmbeddedFarm(const EmbeddedFarmOptions& options = {});
  // Drains the workers and stops the coordinator.
  ~EmbeddedFarm();
  EmbeddedFarm(const EmbeddedFarm&) = delete;
  EmbeddedFarm& operator=(const EmbeddedFarm&) = delete;

  std::string address() const { return address_; }
  Coordinator& coordinator() { return *coordinator_; }
  FarmClient& client() { return *client_; }

  // Submits a job and returns its id. Throws FarmCallError (e.g. INVALID_ARGUMENT).
  std::string submit(const v1::JobSpec& spec);
  // Waits for the job to end, calling `progress` with each event; returns its final status.
  v1::JobStatus wait(const std::string& job_id,
                     const std::function<void(const v1::JobStatus&)>& progress = {});
  // The finished job's image: color and variance of the mean. Throws when it is not done.
  Film film(const std::string& job_id);
  // submit + wait + film; throws std::runtime_error when the job fails or is cancelled.
  Film run(const v1::JobSpec& spec, const std::function<void(const v1::JobStatus&)>& progress = {});

 private:
  std::string data_dir_;
  bool remove_data_dir_ = false;
  std::unique_ptr<Coordinator> coordinator_;
  std::unique_ptr<CoordinatorServer> server_;
  std::string address_;
  std::unique_ptr<FarmClient> client_;
  std::vector<std::unique_ptr<RenderWorker>> workers_;
  std::vector<std::thread> worker_threads_;
};

}  // namespace penumbra::farm
