#include "server/coordinator_server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <stdexcept>

namespace penumbra::farm {

CoordinatorServer::CoordinatorServer(Coordinator& coordinator,
                                     const CoordinatorServerOptions& options)
    : jobs_(coordinator), workers_(coordinator) {
  BatchManagerOptions batch_options;
  batch_options.data_dir = coordinator.options().data_dir;
  batch_options.max_spp = coordinator.options().max_spp;
  batch_options.calibration_share = std::clamp(options.batch_calibration_share, 1e-3, 1.0);
  batch_manager_ =
      std::make_unique<BatchManager>(coordinator, coordinator.scene_parser(), batch_options);
  batches_ = std::make_unique<BatchesService>(*batch_manager_);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  auto credentials = options.credentials ? options.credentials : grpc::InsecureServerCredentials();
  builder.AddListeningPort(options.address, credentials, &port_);
  builder.RegisterService(&jobs_);
  builder.RegisterService(&workers_);
  builder.RegisterService(batches_.get());
  builder.SetMaxReceiveMessageSize(int(std::min<size_t>(options.max_message_bytes, INT_MAX)));
  builder.SetMaxSendMessageSize(int(std::min<size_t>(options.max_message_bytes, INT_MAX)));
  for (const auto& configure : options.configure) configure(builder);
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) throw std::runtime_error("cannot listen on " + options.address);
}

CoordinatorServer::CoordinatorServer(Coordinator& coordinator, const std::string& address,
                                     size_t max_message_bytes)
    : CoordinatorServer(coordinator,
                        CoordinatorServerOptions{address, max_message_bytes, {}, {}, 0.08}) {}

CoordinatorServer::~CoordinatorServer() {
  shutdown();
}

void CoordinatorServer::wait() {
  server_->Wait();
}

void CoordinatorServer::shutdown() {
  if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
}

}  // namespace penumbra::farm
