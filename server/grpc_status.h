#pragma once
// The one place where domain errors become gRPC statuses.

#include <grpcpp/support/status.h>

#include <exception>
#include <new>
#include <utility>

#include "core/scene/scene.h"
#include "server/farm_error.h"

namespace penumbra::farm {

grpc::Status to_status(const FarmError& error);

// Runs `body`, mapping what it throws to a status: FarmError by its code, FormatError to
// INVALID_ARGUMENT, std::bad_alloc to RESOURCE_EXHAUSTED, anything else to INTERNAL.
template <typename Body>
grpc::Status handle(Body&& body) {
  try {
    std::forward<Body>(body)();
    return grpc::Status::OK;
  } catch (const FarmError& error) {
    return to_status(error);
  } catch (const FormatError& error) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, error.what());
  } catch (const std::bad_alloc&) {
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "out of memory");
  } catch (const std::exception& error) {
    return grpc::Status(grpc::StatusCode::INTERNAL, error.what());
  }
}

}  // namespace penumbra::farm
