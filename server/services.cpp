#include "server/services.h"

#include <algorithm>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "server/auth.h"
#include "server/grpc_status.h"

namespace penumbra::farm {

namespace {

struct ClientLimitsState {
  std::mutex mutex;
  ClientLimits limits;
};

ClientLimitsState& client_limits_state() {
  static ClientLimitsState state;
  return state;
}

// The auth interceptor's refusal of this call (server/auth.h), if it refused it. The interceptor
// has already ended the call with that status; the handler only stops here.
std::optional<grpc::Status> refusal(const grpc::CallbackServerContext* context) {
  std::optional<CallAuthorization> authorization = call_authorization(context);
  if (authorization && !authorization->status.ok()) return authorization->status;
  return std::nullopt;
}

template <typename Body>
grpc::ServerUnaryReactor* unary(grpc::CallbackServerContext* context, Body&& body) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  if (std::optional<grpc::Status> refused = refusal(context))
    reactor->Finish(*refused);
  else
    reactor->Finish(handle(std::forward<Body>(body)));
  return reactor;
}

// A streaming call refused before it started.
template <typename Message>
class RefusedWriteReactor final : public grpc::ServerWriteReactor<Message> {
 public:
  explicit RefusedWriteReactor(const grpc::Status& status) { this->Finish(status); }
  void OnDone() override { delete this; }
};

bool is_terminal(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

// WatchJob: writes the job's status whenever the coordinator says it changed (coalescing
// changes that arrive during a write), and finishes after writing a final state.
class WatchReactor final : public grpc::ServerWriteReactor<v1::JobStatus> {
 public:
  WatchReactor(Coordinator& coordinator, CallContext caller, const std::string& job_id)
      : coordinator_(coordinator),
        caller_(std::move(caller)),
        job_id_(job_id),
        link_(std::make_shared<Link>()) {
    link_->reactor = this;
    grpc::Status status = handle([&] {
      std::weak_ptr<Link> link = link_;
      subscription_ = coordinator_.subscribe(caller_, job_id_, [link] {
        if (auto shared = link.lock()) {
          std::lock_guard lock(shared->mutex);
          if (shared->reactor) shared->reactor->on_change_locked();
        }
      });
      subscribed_ = true;
    });
    std::lock_guard lock(link_->mutex);
    if (!status.ok()) {
      finish_locked(status);
      return;
    }
    on_change_locked();
  }

  void OnWriteDone(bool ok) override {
    std::lock_guard lock(link_->mutex);
    writing_ = false;
    if (!ok || cancelled_) {
      finish_locked(grpc::Status(grpc::StatusCode::CANCELLED, "watch cancelled"));
    } else if (wrote_final_) {
      finish_locked(grpc::Status::OK);
    } else if (dirty_) {
      write_locked();
    }
  }

  void OnCancel() override {
    std::lock_guard lock(link_->mutex);
    cancelled_ = true;
    if (!writing_) finish_locked(grpc::Status(grpc::StatusCode::CANCELLED, "watch cancelled"));
  }

  void OnDone() override {
    {
      std::lock_guard lock(link_->mutex);
      link_->reactor = nullptr;
    }
    if (subscribed_) coordinator_.unsubscribe(subscription_);
    delete this;
  }

 private:
  struct Link {
    std::mutex mutex;
    WatchReactor* reactor = nullptr;
  };

  void on_change_locked() {
    if (finished_ || wrote_final_) return;
    if (writing_) {
      dirty_ = true;
      return;
    }
    write_locked();
  }

  void write_locked() {
    dirty_ = false;
    grpc::Status status = handle([&] { event_ = coordinator_.status(caller_, job_id_, false); });
    if (!status.ok()) {
      finish_locked(status);
      return;
    }
    wrote_final_ = is_terminal(event_.state());
    writing_ = true;
    StartWrite(&event_);
  }

  void finish_locked(const grpc::Status& status) {
    if (finished_) return;
    finished_ = true;
    Finish(status);
  }

  Coordinator& coordinator_;
  CallContext caller_;
  std::string job_id_;
  std::shared_ptr<Link> link_;
  uint64_t subscription_ = 0;
  bool subscribed_ = false;
  v1::JobStatus event_;
  bool writing_ = false, dirty_ = false, wrote_final_ = false, finished_ = false,
       cancelled_ = false;
};

// FetchResult: the EXR in chunks of 1 MiB, one write at a time.
class FetchReactor final : public grpc::ServerWriteReactor<v1::ResultChunk> {
 public:
  FetchReactor(Coordinator& coordinator, const CallContext& caller, const std::string& job_id) {
    grpc::Status status = handle([&] { exr_ = coordinator.result_exr(caller, job_id); });
    if (!status.ok()) {
      Finish(status);
      return;
    }
    write_next();
  }
  void OnWriteDone(bool ok) override {
    if (!ok) {
      Finish(grpc::Status(grpc::StatusCode::CANCELLED, "fetch cancelled"));
      return;
    }
    write_next();
  }
  void OnDone() override { delete this; }

 private:
  static constexpr size_t kChunkBytes = size_t(1) << 20;
  void write_next() {
    if (offset_ >= exr_.size() && offset_ != 0) {
      Finish(grpc::Status::OK);
      return;
    }
    size_t size = std::min(kChunkBytes, exr_.size() - offset_);
    chunk_.set_data(exr_.substr(offset_, size));
    chunk_.set_total_bytes(exr_.size());
    offset_ += std::max<size_t>(size, 1);
    StartWrite(&chunk_);
  }
  std::string exr_;
  size_t offset_ = 0;
  v1::ResultChunk chunk_;
};

// A client-streaming call refused before it started.
template <typename Message>
class RefusedReadReactor final : public grpc::ServerReadReactor<Message> {
 public:
  explicit RefusedReadReactor(const grpc::Status& status) { this->Finish(status); }
  void OnDone() override { delete this; }
};

// UploadScene: the manifest, then chunks, each checked and stored as it arrives (so a stream
// cut short keeps what it delivered); at the end of the stream the scene is assembled when
// complete (server/scene_transfer.h).
class UploadReactor final : public grpc::ServerReadReactor<v1::SceneUploadMessage> {
 public:
  UploadReactor(SceneTransfer& transfer, v1::SceneUploadState* response)
      : transfer_(transfer), response_(response) {
    StartRead(&message_);
  }
  void OnReadDone(bool ok) override {
    if (!ok) {
      // The client closed its side (or the call broke: then Finish is ignored).
      if (!have_manifest_) {
        Finish(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            "the upload stream ended before its manifest"));
        return;
      }
      Finish(handle([&] { *response_ = transfer_.finish(manifest_, chunks_stored_); }));
      return;
    }
    grpc::Status status = handle([&] {
      if (!have_manifest_) {
        if (!message_.has_manifest())
          throw FarmError(FarmErrorCode::InvalidArgument,
                          "the upload stream's first message must be the manifest");
        transfer_.check_manifest(message_.manifest());
        manifest_ = message_.manifest();
        have_manifest_ = true;
        return;
      }
      if (!message_.has_chunk())
        throw FarmError(FarmErrorCode::InvalidArgument,
                        "after the manifest, an upload stream carries only chunks");
      if (transfer_.put_chunk(manifest_, message_.chunk())) ++chunks_stored_;
    });
    if (!status.ok()) {
      Finish(status);
      return;
    }
    StartRead(&message_);
  }
  void OnDone() override { delete this; }

 private:
  SceneTransfer& transfer_;
  v1::SceneUploadState* response_;
  v1::SceneUploadMessage message_;
  v1::SceneManifest manifest_;
  bool have_manifest_ = false;
  uint32_t chunks_stored_ = 0;
};

}  // namespace

void set_client_limits(const ClientLimits& limits) {
  std::lock_guard lock(client_limits_state().mutex);
  client_limits_state().limits = limits;
}

grpc::ServerUnaryReactor* JobsService::SubmitJob(grpc::CallbackServerContext* context,
                                                 const v1::SubmitJobRequest* request,
                                                 v1::SubmitJobResponse* response) {
  return unary(context, [&] {
    // The owner is whoever authenticated (empty with authentication off), never what the
    // request says: the coordinator sets it from the caller.
    const CallContext caller = call_context_of(context);
    const v1::JobSpec& spec = request->spec();
    const std::string& owner = caller.client;
    ClientLimitsState& state = client_limits_state();
    std::unique_lock lock(state.mutex);
    const size_t max_queued = state.limits.max_queued_jobs_per_owner;
    if (max_queued == 0) {
      lock.unlock();
      *response = coordinator_.submit(caller, spec);
      return;
    }
    // Counting and submitting under one lock: concurrent submissions of one owner cannot both
    // slip under the limit.
    size_t queued = 0;
    for (const v1::JobStatus& job : coordinator_.list())
      if (job.owner() == owner && !is_terminal(job.state())) ++queued;
    if (queued >= max_queued)
      throw FarmError(
          FarmErrorCode::ResourceExhausted,
          (owner.empty() ? std::string("anonymous clients") : "client \"" + owner + "\"") +
              " already has " + std::to_string(queued) +
              " unfinished jobs, the limit per client "
              "(--max-queued-jobs-per-client " +
              std::to_string(max_queued) + "); wait for one to finish or cancel one");
    *response = coordinator_.submit(caller, spec);
  });
}

grpc::ServerUnaryReactor* JobsService::GetJob(grpc::CallbackServerContext* context,
                                              const v1::GetJobRequest* request,
                                              v1::JobStatus* response) {
  return unary(context, [&] {
    *response = coordinator_.status(call_context_of(context), request->job_id(), true);
  });
}

grpc::ServerUnaryReactor* JobsService::ListJobs(grpc::CallbackServerContext* context,
                                                const v1::ListJobsRequest*,
                                                v1::ListJobsResponse* response) {
  return unary(context, [&] {
    for (v1::JobStatus& job : coordinator_.list(call_context_of(context)))
      *response->add_jobs() = std::move(job);
  });
}

grpc::ServerWriteReactor<v1::JobStatus>* JobsService::WatchJob(grpc::CallbackServerContext* context,
                                                               const v1::WatchJobRequest* request) {
  if (std::optional<grpc::Status> refused = refusal(context))
    return new RefusedWriteReactor<v1::JobStatus>(*refused);
  return new WatchReactor(coordinator_, call_context_of(context), request->job_id());
}

grpc::ServerUnaryReactor* JobsService::CancelJob(grpc::CallbackServerContext* context,
                                                 const v1::CancelJobRequest* request,
                                                 v1::CancelJobResponse* response) {
  return unary(context, [&] {
    response->set_state(coordinator_.cancel(call_context_of(context), request->job_id()));
  });
}

grpc::ServerWriteReactor<v1::ResultChunk>* JobsService::FetchResult(
    grpc::CallbackServerContext* context, const v1::FetchResultRequest* request) {
  if (std::optional<grpc::Status> refused = refusal(context))
    return new RefusedWriteReactor<v1::ResultChunk>(*refused);
  return new FetchReactor(coordinator_, call_context_of(context), request->job_id());
}

grpc::ServerUnaryReactor* JobsService::ListWorkers(grpc::CallbackServerContext* context,
                                                   const v1::ListWorkersRequest*,
                                                   v1::ListWorkersResponse* response) {
  return unary(context, [&] {
    for (v1::WorkerInfo& worker : coordinator_.workers())
      *response->add_workers() = std::move(worker);
  });
}

grpc::ServerUnaryReactor* JobsService::StartSceneUpload(grpc::CallbackServerContext* context,
                                                        const v1::SceneManifest* request,
                                                        v1::SceneUploadState* response) {
  return unary(context, [&] { *response = coordinator_.scene_transfer().start(*request); });
}

grpc::ServerReadReactor<v1::SceneUploadMessage>* JobsService::UploadScene(
    grpc::CallbackServerContext* context, v1::SceneUploadState* response) {
  if (std::optional<grpc::Status> refused = refusal(context))
    return new RefusedReadReactor<v1::SceneUploadMessage>(*refused);
  return new UploadReactor(coordinator_.scene_transfer(), response);
}

grpc::ServerUnaryReactor* WorkersService::Register(grpc::CallbackServerContext* context,
                                                   const v1::RegisterRequest* request,
                                                   v1::RegisterResponse* response) {
  return unary(context, [&] { *response = coordinator_.register_worker(*request); });
}

grpc::ServerUnaryReactor* WorkersService::Heartbeat(grpc::CallbackServerContext* context,
                                                    const v1::HeartbeatRequest* request,
                                                    v1::HeartbeatResponse* response) {
  return unary(context, [&] { *response = coordinator_.heartbeat(*request); });
}

grpc::ServerUnaryReactor* WorkersService::LeaseTasks(grpc::CallbackServerContext* context,
                                                     const v1::LeaseTasksRequest* request,
                                                     v1::LeaseTasksResponse* response) {
  return unary(context, [&] { *response = coordinator_.lease_tasks(*request); });
}

grpc::ServerUnaryReactor* WorkersService::GetScene(grpc::CallbackServerContext* context,
                                                   const v1::GetSceneRequest* request,
                                                   v1::ScenePackage* response) {
  return unary(context, [&] { *response = coordinator_.scene(request->scene_hash()); });
}

grpc::ServerUnaryReactor* WorkersService::GetSceneManifest(grpc::CallbackServerContext* context,
                                                           const v1::GetSceneRequest* request,
                                                           v1::SceneManifest* response) {
  return unary(context,
               [&] { *response = coordinator_.scene_transfer().manifest(request->scene_hash()); });
}

grpc::ServerUnaryReactor* WorkersService::GetSceneChunk(grpc::CallbackServerContext* context,
                                                        const v1::GetSceneChunkRequest* request,
                                                        v1::SceneChunk* response) {
  return unary(context, [&] {
    *response = coordinator_.scene_transfer().chunk(request->scene_hash(), request->index());
  });
}

grpc::ServerUnaryReactor* WorkersService::CompleteTask(grpc::CallbackServerContext* context,
                                                       const v1::CompleteTaskRequest* request,
                                                       v1::CompleteTaskResponse* response) {
  return unary(context, [&] { response->set_accepted(coordinator_.complete_task(*request)); });
}

grpc::ServerUnaryReactor* WorkersService::FailTask(grpc::CallbackServerContext* context,
                                                   const v1::FailTaskRequest* request,
                                                   v1::FailTaskResponse*) {
  return unary(context, [&] { coordinator_.fail_task(*request); });
}

}  // namespace penumbra::farm
