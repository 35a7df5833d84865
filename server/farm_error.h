#pragma once
// Domain errors of the farm. The coordinator's core throws these; the gRPC handlers map them to
// a status in one place (server/grpc_status.h), so the core never sees gRPC.

#include <stdexcept>
#include <string>

namespace penumbra::farm {

enum class FarmErrorCode {
  InvalidArgument,     // malformed scene, unknown method, zero budget, bad tile bytes
  NotFound,            // unknown job, scene or worker
  ResourceExhausted,   // oversized scene, too many queued tasks
  FailedPrecondition,  // wrong build or protocol, result of a job that is not done
  AlreadyExists,       // a worker name held by a live worker
  Internal,
};

class FarmError : public std::runtime_error {
 public:
  FarmError(FarmErrorCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  FarmErrorCode code() const { return code_; }

 private:
  FarmErrorCode code_;
};

}  // namespace penumbra::farm
