#include "proto/support/farm_client.h"

#include <grpcpp/client_context.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include <thread>

namespace penumbra::farm {

namespace {

bool is_terminal(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

}  // namespace

std::string status_code_name(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    default:
      return "status " + std::to_string(int(code));
  }
}

std::shared_ptr<grpc::Channel> make_farm_channel(const std::string& address) {
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(1 << 30);
  arguments.SetMaxSendMessageSize(1 << 30);
  arguments.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  arguments.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 100);
  arguments.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 1000);
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), arguments);
}

FarmClient::FarmClient(const std::string& address)
    : address_(address), channel_(make_farm_channel(address)), stub_(v1::Jobs::NewStub(channel_)) {}

namespace {

void check(const grpc::Status& status, const std::string& address) {
  if (status.ok()) return;
  std::string message = status_code_name(status.error_code()) + ": " + status.error_message();
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE)
    message = "the coordinator at " + address + " is unreachable (" + status.error_message() + ")";
  throw FarmCallError(status.error_code(), message);
}

std::unique_ptr<grpc::ClientContext> call_context(
    std::chrono::seconds seconds = std::chrono::seconds(120)) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + seconds);
  return context;
}

}  // namespace

v1::SubmitJobResponse FarmClient::submit(const v1::JobSpec& spec) {
  v1::SubmitJobRequest request;
  *request.mutable_spec() = spec;
  v1::SubmitJobResponse response;
  auto context = call_context();
  check(stub_->SubmitJob(context.get(), request, &response), address_);
  return response;
}

v1::JobStatus FarmClient::status(const std::string& job_id) {
  v1::GetJobRequest request;
  request.set_job_id(job_id);
  v1::JobStatus response;
  auto context = call_context();
  check(stub_->GetJob(context.get(), request, &response), address_);
  return response;
}

std::vector<v1::JobStatus> FarmClient::list() {
  v1::ListJobsResponse response;
  auto context = call_context();
  check(stub_->ListJobs(context.get(), v1::ListJobsRequest(), &response), address_);
  return {response.jobs().begin(), response.jobs().end()};
}

v1::JobState FarmClient::cancel(const std::string& job_id) {
  v1::CancelJobRequest request;
  request.set_job_id(job_id);
  v1::CancelJobResponse response;
  auto context = call_context();
  check(stub_->CancelJob(context.get(), request, &response), address_);
  return response.state();
}

std::string FarmClient::fetch(const std::string& job_id) {
  v1::FetchResultRequest request;
  request.set_job_id(job_id);
  auto context = call_context(std::chrono::seconds(600));
  auto reader = stub_->FetchResult(context.get(), request);
  std::string bytes;
  v1::ResultChunk chunk;
  while (reader->Read(&chunk)) {
    if (bytes.empty()) bytes.reserve(chunk.total_bytes());
    bytes += chunk.data();
  }
  check(reader->Finish(), address_);
  return bytes;
}

std::vector<v1::WorkerInfo> FarmClient::workers() {
  v1::ListWorkersResponse response;
  auto context = call_context();
  check(stub_->ListWorkers(context.get(), v1::ListWorkersRequest(), &response), address_);
  return {response.workers().begin(), response.workers().end()};
}

v1::JobStatus FarmClient::watch(const std::string& job_id,
                                const std::function<void(const v1::JobStatus&)>& on_event,
                                std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::system_clock::now() + timeout;
  v1::JobStatus last;
  while (true) {
    grpc::ClientContext context;
    context.set_deadline(deadline);
    v1::WatchJobRequest request;
    request.set_job_id(job_id);
    auto reader = stub_->WatchJob(&context, request);
    v1::JobStatus event;
    while (reader->Read(&event)) {
      last = event;
      if (on_event) on_event(event);
    }
    grpc::Status status = reader->Finish();
    if (status.ok() && is_terminal(last.state())) return last;
    bool retry = status.ok() || status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                 status.error_code() == grpc::StatusCode::CANCELLED;
    if (!retry || std::chrono::system_clock::now() >= deadline) {
      if (status.ok()) status = grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "watch ended");
      check(status, address_);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

v1::JobStatus FarmClient::wait(const std::string& job_id, std::chrono::milliseconds timeout) {
  return watch(job_id, nullptr, timeout);
}

}  // namespace penumbra::farm
