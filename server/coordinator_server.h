#pragma once
// Starts the coordinator's gRPC server: jobs, workers and batches services, health checking
// (grpc.health.v1) and server reflection, on one address. The batches service's manager
// (server/batch_manager.h) lives here, with its state in the coordinator's data dir.

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server.h>
#include <grpcpp/server_builder.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "server/batch_manager.h"
#include "server/batch_service.h"
#include "server/coordinator.h"
#include "server/services.h"

namespace penumbra::farm {

struct CoordinatorServerOptions {
  std::string address = "127.0.0.1:7420";  // "host:port"; port 0 picks a free one
  size_t max_message_bytes = size_t(272) << 20;
  // Null: insecure (plain TCP). Set for TLS (server/main.cpp builds it from its flags).
  std::shared_ptr<grpc::ServerCredentials> credentials;
  // Called on the builder after the services are registered and before it starts: interceptors
  // (authentication), further services, channel arguments.
  std::vector<std::function<void(grpc::ServerBuilder&)>> configure;
  // The share of each batch method's budget an equal-time job's calibration renders for
  // (server/batch_manager.h).
  double batch_calibration_share = 0.05;
};

class CoordinatorServer {
 public:
  // Throws std::runtime_error when it cannot listen.
  CoordinatorServer(Coordinator& coordinator, const CoordinatorServerOptions& options);
  // Insecure, on `address`.
  CoordinatorServer(Coordinator& coordinator, const std::string& address, size_t max_message_bytes);
  ~CoordinatorServer();
  int port() const { return port_; }
  BatchManager& batches() { return *batch_manager_; }
  void wait();
  void shutdown();

 private:
  JobsService jobs_;
  WorkersService workers_;
  std::unique_ptr<BatchManager> batch_manager_;
  std::unique_ptr<BatchesService> batches_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

}  // namespace penumbra::farm
