#include "server/batch_service.h"

#include <optional>

#include "server/auth.h"
#include "server/grpc_status.h"

namespace penumbra::farm {

namespace {

// The auth interceptor's refusal of this call (server/auth.h), if it refused it.
std::optional<grpc::Status> refusal(const grpc::ServerContext* context) {
  std::optional<CallAuthorization> authorization = call_authorization(context);
  if (authorization && !authorization->status.ok()) return authorization->status;
  return std::nullopt;
}

template <typename Body>
grpc::Status guarded(const grpc::ServerContext* context, Body&& body) {
  if (std::optional<grpc::Status> refused = refusal(context)) return *refused;
  return handle(std::forward<Body>(body));
}

}  // namespace

grpc::Status BatchesService::SubmitBatch(grpc::ServerContext* context,
                                         const v1::SubmitBatchRequest* request,
                                         v1::SubmitBatchResponse* response) {
  return guarded(context, [&] { *response = manager_.submit(*request, call_context_of(context)); });
}

grpc::Status BatchesService::GetBatch(grpc::ServerContext* context,
                                      const v1::GetBatchRequest* request,
                                      v1::BatchStatus* response) {
  return guarded(context, [&] {
    *response = manager_.status(request->batch_id(), true, call_context_of(context));
  });
}

grpc::Status BatchesService::WatchBatch(grpc::ServerContext* context,
                                        const v1::WatchBatchRequest* request,
                                        grpc::ServerWriter<v1::BatchStatus>* writer) {
  return guarded(context, [&] {
    const CallContext caller = call_context_of(context);
    std::string last;
    uint64_t seen = manager_.version();
    while (!context->IsCancelled()) {
      v1::BatchStatus status = manager_.status(request->batch_id(), false, caller);
      // wall_seconds changes all the time: compare without it.
      v1::BatchStatus compared = status;
      compared.clear_wall_seconds();
      std::string bytes = compared.SerializeAsString();
      if (bytes != last) {
        if (!writer->Write(status)) return;
        last = std::move(bytes);
      }
      if (BatchManager::is_terminal(status.state())) return;
      seen = manager_.wait_for_change(seen, std::chrono::milliseconds(500));
    }
    throw FarmError(FarmErrorCode::Internal, "watch cancelled");
  });
}

grpc::Status BatchesService::ListBatches(grpc::ServerContext* context,
                                         const v1::ListBatchesRequest*,
                                         v1::ListBatchesResponse* response) {
  return guarded(context, [&] {
    for (v1::BatchStatus& status : manager_.list(call_context_of(context)))
      *response->add_batches() = std::move(status);
  });
}

grpc::Status BatchesService::CancelBatch(grpc::ServerContext* context,
                                         const v1::CancelBatchRequest* request,
                                         v1::BatchStatus* response) {
  return guarded(
      context, [&] { *response = manager_.cancel(request->batch_id(), call_context_of(context)); });
}

grpc::Status BatchesService::FetchBatchReference(grpc::ServerContext* context,
                                                 const v1::FetchBatchReferenceRequest* request,
                                                 grpc::ServerWriter<v1::ResultChunk>* writer) {
  return guarded(context, [&] {
    std::string exr = manager_.reference_exr(request->batch_id(), call_context_of(context));
    constexpr size_t kChunkBytes = size_t(1) << 20;
    for (size_t offset = 0; offset < exr.size(); offset += kChunkBytes) {
      v1::ResultChunk chunk;
      chunk.set_data(exr.substr(offset, kChunkBytes));
      chunk.set_total_bytes(exr.size());
      if (!writer->Write(chunk)) return;
    }
  });
}

}  // namespace penumbra::farm
