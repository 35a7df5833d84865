#pragma once
// The coordinator's two gRPC services (callback API). Handlers only translate: request in,
// a call to the Coordinator, response or status out (server/grpc_status.h).

#include "penumbra/v1/farm.grpc.pb.h"
#include "server/coordinator.h"

namespace penumbra::farm {

// Limits per client (per JobSpec.owner: the authenticated name, or one shared anonymous owner
// with authentication off). 0: no limit.
struct ClientLimits {
  size_t max_queued_jobs_per_owner = 0;  // unfinished (queued or running) jobs
};
// Process-wide: CoordinatorServer builds the JobsService from the coordinator alone.
void set_client_limits(const ClientLimits& limits);

// Both services consult the auth interceptor's decision (server/auth.h) first; JobsService sets
// JobSpec.owner to the authenticated caller and enforces ClientLimits in SubmitJob.
class JobsService final : public v1::Jobs::CallbackService {
 public:
  explicit JobsService(Coordinator& coordinator) : coordinator_(coordinator) {}

  grpc::ServerUnaryReactor* SubmitJob(grpc::CallbackServerContext* context,
                                      const v1::SubmitJobRequest* request,
                                      v1::SubmitJobResponse* response) override;
  grpc::ServerUnaryReactor* GetJob(grpc::CallbackServerContext* context,
                                   const v1::GetJobRequest* request,
                                   v1::JobStatus* response) override;
  grpc::ServerUnaryReactor* ListJobs(grpc::CallbackServerContext* context,
                                     const v1::ListJobsRequest* request,
                                     v1::ListJobsResponse* response) override;
  grpc::ServerWriteReactor<v1::JobStatus>* WatchJob(grpc::CallbackServerContext* context,
                                                    const v1::WatchJobRequest* request) override;
  grpc::ServerUnaryReactor* CancelJob(grpc::CallbackServerContext* context,
                                      const v1::CancelJobRequest* request,
                                      v1::CancelJobResponse* response) override;
  grpc::ServerWriteReactor<v1::ResultChunk>* FetchResult(
      grpc::CallbackServerContext* context, const v1::FetchResultRequest* request) override;
  grpc::ServerUnaryReactor* ListWorkers(grpc::CallbackServerContext* context,
                                        const v1::ListWorkersRequest* request,
                                        v1::ListWorkersResponse* response) override;
  grpc::ServerUnaryReactor* StartSceneUpload(grpc::CallbackServerContext* context,
                                             const v1::SceneManifest* request,
                                             v1::SceneUploadState* response) override;
  grpc::ServerReadReactor<v1::SceneUploadMessage>* UploadScene(
      grpc::CallbackServerContext* context, v1::SceneUploadState* response) override;

 private:
  Coordinator& coordinator_;
};

class WorkersService final : public v1::Workers::CallbackService {
 public:
  explicit WorkersService(Coordinator& coordinator) : coordinator_(coordinator) {}

  grpc::ServerUnaryReactor* Register(grpc::CallbackServerContext* context,
                                     const v1::RegisterRequest* request,
                                     v1::RegisterResponse* response) override;
  grpc::ServerUnaryReactor* Heartbeat(grpc::CallbackServerContext* context,
                                      const v1::HeartbeatRequest* request,
                                      v1::HeartbeatResponse* response) override;
  grpc::ServerUnaryReactor* LeaseTasks(grpc::CallbackServerContext* context,
                                       const v1::LeaseTasksRequest* request,
                                       v1::LeaseTasksResponse* response) override;
  grpc::ServerUnaryReactor* GetScene(grpc::CallbackServerContext* context,
                                     const v1::GetSceneRequest* request,
                                     v1::ScenePackage* response) override;
  grpc::ServerUnaryReactor* GetSceneManifest(grpc::CallbackServerContext* context,
                                             const v1::GetSceneRequest* request,
                                             v1::SceneManifest* response) override;
  grpc::ServerUnaryReactor* GetSceneChunk(grpc::CallbackServerContext* context,
                                          const v1::GetSceneChunkRequest* request,
                                          v1::SceneChunk* response) override;
  grpc::ServerUnaryReactor* CompleteTask(grpc::CallbackServerContext* context,
                                         const v1::CompleteTaskRequest* request,
                                         v1::CompleteTaskResponse* response) override;
  grpc::ServerUnaryReactor* FailTask(grpc::CallbackServerContext* context,
                                     const v1::FailTaskRequest* request,
                                     v1::FailTaskResponse* response) override;

 private:
  Coordinator& coordinator_;
};

}  // namespace penumbra::farm
