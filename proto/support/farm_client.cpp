#include "proto/support/farm_client.h"

#include <grpcpp/client_context.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/client_interceptor.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include "proto/support/scene_chunks.h"

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
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    case grpc::StatusCode::UNKNOWN:
      return "UNKNOWN";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    default:
      return "status " + std::to_string(int(code));
  }
}

namespace {

grpc::ChannelArguments farm_channel_arguments() {
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(1 << 30);
  arguments.SetMaxSendMessageSize(1 << 30);
  arguments.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  arguments.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 100);
  arguments.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 1000);
  return arguments;
}

std::string read_pem(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in || text.str().empty()) throw std::runtime_error("cannot read the " + what + " " + path);
  return text.str();
}

std::string trim(const std::string& text) {
  const char* space = " \t\r\n";
  size_t begin = text.find_first_not_of(space);
  if (begin == std::string::npos) return "";
  return text.substr(begin, text.find_last_not_of(space) - begin + 1);
}

// Adds "authorization: Bearer <token>" to the initial metadata of every call.
class BearerTokenInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit BearerTokenInterceptor(std::string header) : header_(std::move(header)) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA))
      methods->GetSendInitialMetadata()->emplace("authorization", header_);
    methods->Proceed();
  }

 private:
  std::string header_;
};

class BearerTokenInterceptorFactory final
    : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit BearerTokenInterceptorFactory(const std::string& token) : header_("Bearer " + token) {}
  grpc::experimental::Interceptor* CreateClientInterceptor(
      grpc::experimental::ClientRpcInfo*) override {
    return new BearerTokenInterceptor(header_);
  }

 private:
  std::string header_;
};

}  // namespace

std::shared_ptr<grpc::Channel> make_farm_channel(const std::string& address) {
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(),
                                   farm_channel_arguments());
}

bool is_loopback_address(const std::string& address) {
  std::string target = address;
  for (const char* scheme : {"dns:///", "dns:", "ipv4:", "ipv6:"})
    if (target.rfind(scheme, 0) == 0) {
      target = target.substr(std::string(scheme).size());
      break;
    }
  if (target.rfind("unix:", 0) == 0 || target.rfind("unix-abstract:", 0) == 0) return true;
  std::string host;
  if (!target.empty() && target.front() == '[') {
    size_t close = target.find(']');
    if (close == std::string::npos) return false;
    host = target.substr(1, close - 1);
  } else {
    size_t colon = target.rfind(':');
    host = colon == std::string::npos ? target : target.substr(0, colon);
    // A bare IPv6 address without a port ("::1").
    if (std::count(target.begin(), target.end(), ':') > 1) host = target;
  }
  std::transform(host.begin(), host.end(), host.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (host == "localhost" || host == "::1" || host == "0:0:0:0:0:0:0:1") return true;
  // 127.0.0.0/8, written as a dotted quad.
  if (host.rfind("127.", 0) != 0) return false;
  int dots = 0;
  for (char c : host) {
    if (c == '.')
      ++dots;
    else if (c < '0' || c > '9')
      return false;
  }
  return dots == 3;
}

std::string resolve_token(const std::string& token, const std::string& token_file) {
  if (!token.empty()) return token;
  if (!token_file.empty()) {
    std::ifstream in(token_file);
    std::string line;
    if (!in || !std::getline(in, line) || trim(line).empty())
      throw std::runtime_error("cannot read a token from " + token_file);
    return trim(line);
  }
  const char* env = std::getenv("PENUMBRA_TOKEN");
  return env ? trim(env) : std::string();
}

std::shared_ptr<grpc::Channel> make_farm_channel(const FarmConnection& connection) {
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (connection.uses_tls()) {
    grpc::SslCredentialsOptions ssl;
    if (!connection.tls_ca.empty()) ssl.pem_root_certs = read_pem(connection.tls_ca, "CA file");
    if (connection.tls_cert.empty() != connection.tls_key.empty())
      throw std::runtime_error(
          "mutual TLS needs both a certificate (--tls-cert) and its key "
          "(--tls-key)");
    if (!connection.tls_cert.empty()) {
      ssl.pem_cert_chain = read_pem(connection.tls_cert, "certificate");
      ssl.pem_private_key = read_pem(connection.tls_key, "private key");
    }
    credentials = grpc::SslCredentials(ssl);
  } else {
    if (!connection.token.empty() && !is_loopback_address(connection.address))
      throw std::runtime_error(
          "refusing to send a token in plaintext to " + connection.address +
          ": use TLS (--tls-ca) or a loopback address (127.0.0.1, localhost, ::1)");
    credentials = grpc::InsecureChannelCredentials();
  }
  if (connection.token.empty())
    return grpc::CreateCustomChannel(connection.address, credentials, farm_channel_arguments());
  if (connection.token.find_first_of("\r\n") != std::string::npos)
    throw std::runtime_error("the token contains a line break");
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(std::make_unique<BearerTokenInterceptorFactory>(connection.token));
  return grpc::experimental::CreateCustomChannelWithInterceptors(
      connection.address, credentials, farm_channel_arguments(), std::move(interceptors));
}

FarmClient::FarmClient(const std::string& address)
    : address_(address), channel_(make_farm_channel(address)), stub_(v1::Jobs::NewStub(channel_)) {}

FarmClient::FarmClient(const FarmConnection& connection)
    : address_(connection.address),
      channel_(make_farm_channel(connection)),
      stub_(v1::Jobs::NewStub(channel_)) {}

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

SceneUploadResult upload_scene(v1::Jobs::Stub& stub, const std::string& address,
                               const v1::ScenePackage& package, const std::string& scene_hash,
                               const SceneUploadOptions& options) {
  const std::string bytes = serialize_package(package);
  const v1::SceneManifest manifest = make_scene_manifest(scene_hash, bytes, options.chunk_bytes);
  SceneUploadResult result;
  result.scene_hash = scene_hash;
  result.chunks_total = uint32_t(manifest.chunk_hashes_size());
  v1::SceneUploadState state;
  {
    auto context = call_context();
    check(stub.StartSceneUpload(context.get(), manifest, &state), address);
  }
  if (state.complete()) {
    result.complete = result.already_stored = true;
    return result;
  }
  // A chunk the coordinator had at the start may be gone at the end (the upload of another
  // scene that shares it finished and dropped it): then another round sends what is missing.
  for (int round = 0; round < 3 && !state.complete(); ++round) {
    auto context = call_context(std::chrono::seconds(3600));
    v1::SceneUploadState done;
    std::unique_ptr<grpc::ClientWriter<v1::SceneUploadMessage>> writer =
        stub.UploadScene(context.get(), &done);
    v1::SceneUploadMessage message;
    *message.mutable_manifest() = manifest;
    bool open = writer->Write(message);
    for (uint32_t index : state.missing_chunks()) {
      if (!open) break;
      if (options.stop_after_chunks && result.chunks_sent >= options.stop_after_chunks) break;
      v1::SceneChunk& chunk = *message.mutable_chunk();
      chunk.set_index(index);
      const size_t begin = size_t(index) * manifest.chunk_bytes();
      chunk.set_data(bytes.substr(begin, scene_chunk_size(manifest, index)));
      open = writer->Write(message);
      if (open) ++result.chunks_sent;
    }
    writer->WritesDone();
    check(writer->Finish(), address);
    state = done;
    if (options.stop_after_chunks) break;
  }
  result.complete = state.complete();
  if (!result.complete && !options.stop_after_chunks)
    throw FarmCallError(grpc::StatusCode::ABORTED,
                        "scene " + scene_hash.substr(0, 12) + ": " +
                            std::to_string(state.missing_chunks_size()) +
                            " chunk(s) still missing after three upload rounds");
  return result;
}

SceneUploadResult FarmClient::upload_scene(const v1::ScenePackage& package,
                                           const std::string& scene_hash,
                                           const SceneUploadOptions& options) {
  return farm::upload_scene(*stub_, address_, package, scene_hash, options);
}

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
