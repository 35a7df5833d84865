#include "server/grpc_status.h"

namespace penumbra::farm {

grpc::Status to_status(const FarmError& error) {
  grpc::StatusCode code = grpc::StatusCode::INTERNAL;
  switch (error.code()) {
    case FarmErrorCode::InvalidArgument:
      code = grpc::StatusCode::INVALID_ARGUMENT;
      break;
    case FarmErrorCode::NotFound:
      code = grpc::StatusCode::NOT_FOUND;
      break;
    case FarmErrorCode::ResourceExhausted:
      code = grpc::StatusCode::RESOURCE_EXHAUSTED;
      break;
    case FarmErrorCode::FailedPrecondition:
      code = grpc::StatusCode::FAILED_PRECONDITION;
      break;
    case FarmErrorCode::AlreadyExists:
      code = grpc::StatusCode::ALREADY_EXISTS;
      break;
    case FarmErrorCode::Internal:
      code = grpc::StatusCode::INTERNAL;
      break;
  }
  return grpc::Status(code, error.what());
}

}  // namespace penumbra::farm
