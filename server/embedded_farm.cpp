#include "server/embedded_farm.h"

#include <filesystem>
#include <random>
#include <stdexcept>

#include "proto/support/scene_packing.h"

namespace penumbra::farm {

EmbeddedFarm::EmbeddedFarm(const EmbeddedFarmOptions& options) {
  data_dir_ = options.data_dir;
  if (data_dir_.empty()) {
    std::random_device random;
    data_dir_ = (std::filesystem::temp_directory_path() /
                 ("penumbra-embedded-farm-" + std::to_string(random()) + std::to_string(random())))
                    .string();
    remove_data_dir_ = true;
  }
  CoordinatorOptions coordinator_options;
  coordinator_options.data_dir = data_dir_;
  coordinator_options.lease_time = options.lease_time;
  coordinator_options.max_scene_bytes = options.max_scene_bytes;
  coordinator_ = std::make_unique<Coordinator>(coordinator_options, parse_wire_package);
  server_ = std::make_unique<CoordinatorServer>(*coordinator_, "127.0.0.1:0",
                                                coordinator_options.max_scene_bytes + (16u << 20));
  address_ = "127.0.0.1:" + std::to_string(server_->port());
  client_ = std::make_unique<FarmClient>(address_);
  for (int i = 0; i < std::max(1, options.workers); ++i) {
    WorkerOptions worker_options;
    worker_options.coordinator = address_;
    worker_options.threads = std::max(1, options.threads_per_worker);
    worker_options.name = "embedded-" + std::to_string(i + 1);
    worker_options.idle_poll = std::chrono::milliseconds(20);
    workers_.push_back(std::make_unique<RenderWorker>(worker_options));
  }
  for (auto& worker : workers_)
    worker_threads_.emplace_back([worker = worker.get()] { worker->run(); });
}

EmbeddedFarm::~EmbeddedFarm() {
  for (auto& worker : workers_) worker->drain();
  for (auto& thread : worker_threads_) thread.join();
  workers_.clear();
  client_.reset();
  server_->shutdown();
  server_.reset();
  coordinator_.reset();
  if (remove_data_dir_) {
    std::error_code error;
    std::filesystem::remove_all(data_dir_, error);
  }
}

std::string EmbeddedFarm::submit(const v1::JobSpec& spec) {
  return client_->submit(spec).job_id();
}

v1::JobStatus EmbeddedFarm::wait(const std::string& job_id,
                                 const std::function<void(const v1::JobStatus&)>& progress) {
  return client_->watch(job_id, progress);
}

Film EmbeddedFarm::film(const std::string& job_id) {
  return coordinator_->result_film(job_id);
}

Film EmbeddedFarm::run(const v1::JobSpec& spec,
                       const std::function<void(const v1::JobStatus&)>& progress) {
  std::string job_id = submit(spec);
  v1::JobStatus status = wait(job_id, progress);
  if (status.state() != v1::JOB_STATE_DONE)
    throw std::runtime_error(job_id + " ended " + v1::JobState_Name(status.state()) + ": " +
                             status.error());
  return film(job_id);
}

}  // namespace penumbra::farm
