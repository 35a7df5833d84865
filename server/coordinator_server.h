#pragma once
// Starts the coordinator's gRPC server: jobs and workers services, health checking
// (grpc.health.v1) and server reflection, on one address.

#include <grpcpp/server.h>

#include <memory>
#include <string>

#include "server/coordinator.h"
#include "server/services.h"

namespace penumbra::farm {

class CoordinatorServer {
 public:
  // Listens on `address` ("host:port"; port 0 picks a free one). Throws std::runtime_error when
  // it cannot listen.
  CoordinatorServer(Coordinator& coordinator, const std::string& address, size_t max_message_bytes);
  ~CoordinatorServer();
  int port() const { return port_; }
  void wait();
  void shutdown();

 private:
  JobsService jobs_;
  WorkersService workers_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

}  // namespace penumbra::farm
