#include "server/coordinator_server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>

#include <chrono>
#include <climits>
#include <stdexcept>

namespace penumbra::farm {

CoordinatorServer::CoordinatorServer(Coordinator& coordinator,
                                     const CoordinatorServerOptions& options)
    : jobs_(coordinator), workers_(coordinator) {
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  auto credentials = options.credentials ? options.credentials : grpc::InsecureServerCredentials();
  builder.AddListeningPort(options.address, credentials, &port_);
  builder.RegisterService(&jobs_);
  builder.RegisterService(&workers_);
  builder.SetMaxReceiveMessageSize(int(std::min<size_t>(options.max_message_bytes, INT_MAX)));
  builder.SetMaxSendMessageSize(int(std::min<size_t>(options.max_message_bytes, INT_MAX)));
  for (const auto& configure : options.configure) configure(builder);
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) throw std::runtime_error("cannot listen on " + options.address);
}

CoordinatorServer::CoordinatorServer(Coordinator& coordinator, const std::string& address,
                                     size_t max_message_bytes)
    : CoordinatorServer(coordinator, CoordinatorServerOptions{address, max_message_bytes, {}, {}}) {
}

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
