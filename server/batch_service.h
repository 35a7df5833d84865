#pragma once
// The Batches gRPC service (penumbra.v1.Batches): translates calls to the BatchManager
// (server/batch_manager.h). Synchronous handlers: WatchBatch holds a thread of the server's
// pool while it streams. Errors: a bad spec is INVALID_ARGUMENT naming the JSON path, an unknown
// batch NOT_FOUND (server/grpc_status.h maps them).

#include "penumbra/v1/farm.grpc.pb.h"
#include "server/batch_manager.h"

namespace penumbra::farm {

class BatchesService final : public v1::Batches::Service {
 public:
  explicit BatchesService(BatchManager& manager) : manager_(manager) {}

  grpc::Status SubmitBatch(grpc::ServerContext* context, const v1::SubmitBatchRequest* request,
                           v1::SubmitBatchResponse* response) override;
  grpc::Status GetBatch(grpc::ServerContext* context, const v1::GetBatchRequest* request,
                        v1::BatchStatus* response) override;
  grpc::Status WatchBatch(grpc::ServerContext* context, const v1::WatchBatchRequest* request,
                          grpc::ServerWriter<v1::BatchStatus>* writer) override;
  grpc::Status ListBatches(grpc::ServerContext* context, const v1::ListBatchesRequest* request,
                           v1::ListBatchesResponse* response) override;
  grpc::Status CancelBatch(grpc::ServerContext* context, const v1::CancelBatchRequest* request,
                           v1::BatchStatus* response) override;
  grpc::Status FetchBatchReference(grpc::ServerContext* context,
                                   const v1::FetchBatchReferenceRequest* request,
                                   grpc::ServerWriter<v1::ResultChunk>* writer) override;

 private:
  BatchManager& manager_;
};

}  // namespace penumbra::farm
