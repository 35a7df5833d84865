#pragma once
// A client of the coordinator's jobs service: what `penumbra submit/watch/...`, the embedded
// farm and the tests use. Failed calls throw FarmCallError with the gRPC code and a readable
// message.

#include <grpcpp/channel.h>

#include <chrono>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "penumbra/v1/farm.grpc.pb.h"

namespace penumbra::farm {

class FarmCallError : public std::runtime_error {
 public:
  FarmCallError(grpc::StatusCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

// "NOT_FOUND", "INVALID_ARGUMENT", ...
std::string status_code_name(grpc::StatusCode code);
// Channel arguments shared by the farm's clients: large messages, quick reconnection.
std::shared_ptr<grpc::Channel> make_farm_channel(const std::string& address);

class FarmClient {
 public:
  explicit FarmClient(const std::string& address);

  v1::SubmitJobResponse submit(const v1::JobSpec& spec);
  v1::JobStatus status(const std::string& job_id);
  std::vector<v1::JobStatus> list();
  v1::JobState cancel(const std::string& job_id);
  std::string fetch(const std::string& job_id);  // the result EXR's bytes
  std::vector<v1::WorkerInfo> workers();
  // Streams progress events to `on_event` until the job ends; returns the final status.
  // Reconnects when the coordinator is away, up to `timeout` in all.
  v1::JobStatus watch(const std::string& job_id,
                      const std::function<void(const v1::JobStatus&)>& on_event,
                      std::chrono::milliseconds timeout = std::chrono::hours(24 * 365));
  // Waits until the job ends; returns its final status. Throws on timeout (DEADLINE_EXCEEDED).
  v1::JobStatus wait(const std::string& job_id, std::chrono::milliseconds timeout);

  v1::Jobs::Stub& stub() { return *stub_; }

 private:
  std::string address_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Jobs::Stub> stub_;
};

}  // namespace penumbra::farm
