#pragma once
// A client of the coordinator's jobs service: what `penumbra submit/watch/...`, the embedded
// farm and the tests use. Failed calls throw FarmCallError with the gRPC code and a readable
// message.
//
// Connections: make_farm_channel(FarmConnection) opens TLS (server authentication with a CA
// file, mutual TLS with a client certificate) or plaintext, and adds the bearer token to every
// call made on the channel ("authorization: Bearer <token>" metadata, added by a client
// interceptor, so it works with and without TLS). A token is refused over plaintext to any host
// but a loopback one (it would travel in the clear).

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

// How to reach and authenticate to a coordinator. Paths name PEM files.
struct FarmConnection {
  std::string address;   // "host:port"
  std::string tls_ca;    // CA certificate(s) that signed the coordinator's; set: TLS
  std::string tls_cert;  // this client's certificate, for mutual TLS (with tls_key); set: TLS
  std::string tls_key;   // this client's private key
  std::string token;     // bearer token; empty: none (the coordinator has authentication off)
  bool tls = false;      // TLS with the system's root certificates when tls_ca is empty
  bool uses_tls() const { return tls || !tls_ca.empty() || !tls_cert.empty(); }
};

// Channel arguments shared by the farm's clients: large messages, quick reconnection.
// Plaintext, no token.
std::shared_ptr<grpc::Channel> make_farm_channel(const std::string& address);
// TLS when connection.uses_tls(); the token (if any) on every call. Throws std::runtime_error for
// a token over plaintext to a host that is not loopback, an unreadable PEM file, or a certificate
// without its key.
std::shared_ptr<grpc::Channel> make_farm_channel(const FarmConnection& connection);

// True for localhost, 127.0.0.0/8, ::1 and unix: addresses.
bool is_loopback_address(const std::string& address);

// The token to use: `token` when set, else the first line of `token_file` (trimmed; throws when
// the file cannot be read or is empty), else the environment variable PENUMBRA_TOKEN, else "".
std::string resolve_token(const std::string& token, const std::string& token_file);

// A scene upload's outcome (upload_scene).
struct SceneUploadResult {
  std::string scene_hash;
  bool complete = false;        // the coordinator stores the scene
  bool already_stored = false;  // it did before this call: nothing was sent
  uint32_t chunks_total = 0;
  uint32_t chunks_sent = 0;  // by this call (chunks the coordinator had are skipped)
};

struct SceneUploadOptions {
  uint32_t chunk_bytes = uint32_t(1) << 20;  // kSceneChunkBytes (proto/support/scene_chunks.h)
  // Ends the stream after sending this many chunks (0: send them all), leaving the upload
  // incomplete: how tests stand in for an upload cut short.
  uint32_t stop_after_chunks = 0;
};

// Uploads a package in chunks (Jobs.StartSceneUpload, then Jobs.UploadScene with the chunks the
// coordinator lacks), so jobs and batches can name it by `scene_hash` (its content hash, as
// core computes it: the coordinator checks it). Throws FarmCallError (RESOURCE_EXHAUSTED over
// the coordinator's scene-size limit, INVALID_ARGUMENT for a scene it cannot parse).
SceneUploadResult upload_scene(v1::Jobs::Stub& stub, const std::string& address,
                               const v1::ScenePackage& package, const std::string& scene_hash,
                               const SceneUploadOptions& options = {});

class FarmClient {
 public:
  explicit FarmClient(const std::string& address);
  explicit FarmClient(const FarmConnection& connection);

  v1::SubmitJobResponse submit(const v1::JobSpec& spec);
  // upload_scene on this client's channel.
  SceneUploadResult upload_scene(const v1::ScenePackage& package, const std::string& scene_hash,
                                 const SceneUploadOptions& options = {});
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
