#include "proto/support/batch_client.h"

#include <grpcpp/client_context.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "core/batch/batch_spec.h"
#include "core/image/image.h"
#include "core/image/metrics.h"
#include "proto/support/scene_packing.h"

namespace penumbra::farm {

namespace {

void check(const grpc::Status& status) {
  if (!status.ok())
    throw FarmCallError(status.error_code(),
                        status_code_name(status.error_code()) + ": " + status.error_message());
}

std::string read_bytes(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError("", "cannot read the " + what + " " + path.string());
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

template <typename Request>
std::string read_chunks(grpc::ClientReader<v1::ResultChunk>& reader) {
  std::string bytes;
  v1::ResultChunk chunk;
  while (reader.Read(&chunk)) bytes += chunk.data();
  check(reader.Finish());
  return bytes;
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + temporary.string());
  }
  std::filesystem::rename(temporary, path);
}

}  // namespace

bool is_terminal(v1::BatchState state) {
  return state == v1::BATCH_STATE_DONE || state == v1::BATCH_STATE_FAILED ||
         state == v1::BATCH_STATE_CANCELLED;
}

BatchClient::BatchClient(const std::string& address)
    : address_(address),
      channel_(make_farm_channel(address)),
      stub_(v1::Batches::NewStub(channel_)),
      jobs_(v1::Jobs::NewStub(channel_)) {}

BatchClient::BatchClient(const FarmConnection& connection)
    : address_(connection.address),
      channel_(make_farm_channel(connection)),
      stub_(v1::Batches::NewStub(channel_)),
      jobs_(v1::Jobs::NewStub(channel_)) {}

v1::SubmitBatchResponse BatchClient::submit(const v1::SubmitBatchRequest& request) {
  grpc::ClientContext context;
  v1::SubmitBatchResponse response;
  check(stub_->SubmitBatch(&context, request, &response));
  return response;
}

v1::SubmitBatchResponse BatchClient::upload_and_submit(v1::SubmitBatchRequest request,
                                                       const std::string& scene_hash) {
  if (request.has_scene()) {
    upload_scene(*jobs_, address_, request.scene(), scene_hash);
    request.clear_scene();
  }
  request.set_scene_hash(scene_hash);
  return submit(request);
}

v1::BatchStatus BatchClient::status(const std::string& batch_id) {
  grpc::ClientContext context;
  v1::GetBatchRequest request;
  request.set_batch_id(batch_id);
  v1::BatchStatus response;
  check(stub_->GetBatch(&context, request, &response));
  return response;
}

std::vector<v1::BatchStatus> BatchClient::list() {
  grpc::ClientContext context;
  v1::ListBatchesResponse response;
  check(stub_->ListBatches(&context, v1::ListBatchesRequest(), &response));
  return {response.batches().begin(), response.batches().end()};
}

v1::BatchStatus BatchClient::cancel(const std::string& batch_id) {
  grpc::ClientContext context;
  v1::CancelBatchRequest request;
  request.set_batch_id(batch_id);
  v1::BatchStatus response;
  check(stub_->CancelBatch(&context, request, &response));
  return response;
}

std::string BatchClient::fetch_reference(const std::string& batch_id) {
  grpc::ClientContext context;
  v1::FetchBatchReferenceRequest request;
  request.set_batch_id(batch_id);
  auto reader = stub_->FetchBatchReference(&context, request);
  return read_chunks<v1::FetchBatchReferenceRequest>(*reader);
}

std::string BatchClient::fetch_result(const std::string& job_id) {
  grpc::ClientContext context;
  v1::FetchResultRequest request;
  request.set_job_id(job_id);
  auto reader = jobs_->FetchResult(&context, request);
  return read_chunks<v1::FetchResultRequest>(*reader);
}

v1::BatchStatus BatchClient::watch(const std::string& batch_id,
                                   const std::function<void(const v1::BatchStatus&)>& on_event,
                                   std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() +
                         (deadline - std::chrono::steady_clock::now()));
    v1::WatchBatchRequest request;
    request.set_batch_id(batch_id);
    auto reader = stub_->WatchBatch(&context, request);
    v1::BatchStatus event;
    bool ended = false;
    while (reader->Read(&event)) {
      if (on_event) on_event(event);
      if (is_terminal(event.state())) ended = true;
    }
    grpc::Status status = reader->Finish();
    if (ended) return this->status(batch_id);
    bool retry = status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                 status.error_code() == grpc::StatusCode::CANCELLED || status.ok();
    if (!retry) check(status);
    if (std::chrono::steady_clock::now() >= deadline)
      throw FarmCallError(grpc::StatusCode::DEADLINE_EXCEEDED,
                          "DEADLINE_EXCEEDED: " + batch_id + " did not end in time");
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

v1::SubmitBatchRequest make_batch_request_from_text(
    const std::string& spec_text, const std::string& source_name, const std::string& base_dir,
    const std::function<std::string(const std::string&)>& bundled_scene_path) {
  BatchSpec spec = parse_batch_spec(spec_text, source_name);
  v1::SubmitBatchRequest request;
  request.set_spec_json(spec_text);
  request.set_source_name(source_name);
  auto resolve = [&](const std::string& path) {
    std::filesystem::path p(path);
    if (p.is_absolute()) return p;
    std::filesystem::path beside = std::filesystem::path(base_dir) / p;
    return std::filesystem::exists(beside) ? beside : p;
  };
  bool is_path = spec.scene.find('/') != std::string::npos ||
                 (spec.scene.size() > 5 && spec.scene.ends_with(".json")) ||
                 (spec.scene.size() > 5 && spec.scene.ends_with(".pbrt"));
  std::string scene_path = is_path ? resolve(spec.scene).string() : bundled_scene_path(spec.scene);
  try {
    *request.mutable_scene() = pack_scene_file(scene_path);
  } catch (const FormatError& error) {
    throw FormatError("$.scene", "cannot pack the scene \"" + spec.scene + "\" (" + scene_path +
                                     "): " + error.what() + " (in " + source_name + ")");
  }
  if (spec.reference.kind == BatchReferenceKind::Exr) {
    std::filesystem::path exr = resolve(spec.reference.exr_path);
    std::ifstream in(exr, std::ios::binary);
    if (!in)
      throw FormatError("$.reference", "cannot read the reference EXR " + exr.string() + " (in " +
                                           source_name + ")");
    request.set_reference_exr(read_bytes(exr, "reference EXR"));
  }
  return request;
}

v1::SubmitBatchRequest make_batch_request(
    const std::string& spec_path,
    const std::function<std::string(const std::string&)>& bundled_scene_path) {
  std::string text = read_bytes(spec_path, "batch spec");
  std::string base = std::filesystem::path(spec_path).parent_path().string();
  return make_batch_request_from_text(text, spec_path, base.empty() ? "." : base,
                                      bundled_scene_path);
}

void write_batch_result(BatchClient& client, const v1::BatchStatus& status,
                        const std::filesystem::path& dir) {
  if (status.state() != v1::BATCH_STATE_DONE)
    throw std::runtime_error(status.batch_id() + " is " + v1::BatchState_Name(status.state()) +
                             (status.error().empty() ? std::string() : ": " + status.error()) +
                             "; only a finished batch has a result folder");
  std::filesystem::create_directories(dir / "runs");
  std::string reference_bytes = client.fetch_reference(status.batch_id());
  write_bytes(dir / "reference.exr", reference_bytes);
  Image reference = decode_exr(reference_bytes);

  std::map<std::string, Region> regions;
  nlohmann::json region_list = nlohmann::json::array();
  for (const v1::BatchRegion& region : status.regions()) {
    Region rect{region.rect().x0(), region.rect().y0(), region.rect().x1(), region.rect().y1()};
    regions[region.name()] = rect;
    region_list.push_back(
        {{"name", region.name()}, {"rect", {rect.x0, rect.y0, rect.x1, rect.y1}}});
  }

  nlohmann::json index;
  index["format"] = "penumbra/batch-result@1";
  index["batch_id"] = status.batch_id();
  index["name"] = status.name();
  index["spec"] = nlohmann::json::parse(status.spec_json(), nullptr, false);
  index["scene"] = {{"name", status.scene_name()},
                    {"hash", status.scene_hash()},
                    {"width", status.width()},
                    {"height", status.height()}};
  index["regions"] = region_list;
  const v1::BatchReferenceStatus& ref = status.reference();
  index["reference"] = {{"exr", "reference.exr"},   {"kind", ref.kind()}, {"method", ref.method()},
                        {"sampler", ref.sampler()}, {"spp", ref.spp()},   {"job_id", ref.job_id()},
                        {"cached", ref.cached()}};
  if (ref.sizing().sized()) {
    const v1::BatchReferenceSizing& sizing = ref.sizing();
    index["reference"]["sizing"] = {{"probe_spp", sizing.probe_spp()},
                                    {"target_share", sizing.target_share()},
                                    {"max_seconds", sizing.max_seconds()},
                                    {"seconds_per_pass", sizing.seconds_per_pass()},
                                    {"required_spp", sizing.required_spp()},
                                    {"capped", sizing.capped()},
                                    {"predicted_share", sizing.predicted_share()},
                                    {"predicted_seconds", sizing.predicted_seconds()},
                                    {"deciding_region", sizing.deciding_region()},
                                    {"best_method", sizing.best_method()}};
  }
  index["wall_seconds"] = status.wall_seconds();
  index["compute_seconds"] = status.compute_seconds();

  std::set<std::string> used_files;
  nlohmann::json methods = nlohmann::json::array();
  for (const v1::BatchMethodStatus& method : status.methods()) {
    nlohmann::json entry;
    entry["label"] = method.label();
    entry["method"] = method.method();
    entry["sampler"] = method.sampler();
    entry["budget_seconds"] =
        method.has_budget_seconds() ? nlohmann::json(method.budget_seconds()) : nlohmann::json();
    if (method.seconds_per_pass() > 0)
      entry["calibration_seconds_per_pass"] = method.seconds_per_pass();
    entry["runs"] = nlohmann::json::array();
    std::string safe = file_safe_label(method.label());
    nlohmann::json failed = nlohmann::json::array();
    for (const v1::BatchRun& run : method.runs()) {
      const v1::JobStatus& job = run.job();
      if (job.state() != v1::JOB_STATE_DONE) {
        failed.push_back({{"job_id", run.job_id()},
                          {"state", v1::JobState_Name(job.state())},
                          {"error", job.error()}});
        continue;
      }
      std::string stem = safe +
                         (run.equal_time() ? "" : ".spp" + std::to_string(run.spp_planned())) +
                         ".r" + std::to_string(run.repeat());
      std::string file = "runs/" + stem + ".exr";
      for (int n = 2; used_files.count(file); ++n)
        file = "runs/" + stem + "-" + std::to_string(n) + ".exr";
      used_files.insert(file);
      std::string bytes = client.fetch_result(run.job_id());
      write_bytes(dir / file, bytes);
      Image image = decode_exr(bytes);
      nlohmann::json errors = nlohmann::json::array();
      for (const auto& [name, summary] : error_summary(image, reference, regions)) {
        nlohmann::json e{
            {"region", name}, {"mrse", summary.mrse}, {"mse", summary.mse}, {"rmse", summary.rmse}};
        if (name == "image")
          errors.insert(errors.begin(), e);
        else
          errors.push_back(e);
      }
      nlohmann::json curve = nlohmann::json::array();
      for (const v1::ErrorSample& point : job.curve()) {
        nlohmann::json regions = nlohmann::json::object();
        for (const v1::RegionError& error : point.regions()) regions[error.region()] = error.mrse();
        curve.push_back({{"passes", point.passes()},
                         {"compute_seconds", point.compute_seconds()},
                         {"wall_seconds", point.wall_seconds()},
                         {"mrse", point.mrse()},
                         {"regions", regions}});
      }
      entry["runs"].push_back({{"repeat", run.repeat()},
                               {"seed", run.seed()},
                               {"job_id", run.job_id()},
                               {"exr", file},
                               {"equal_time", run.equal_time()},
                               {"spp", job.passes_complete()},
                               {"compute_seconds", job.compute_seconds()},
                               {"wall_seconds", job.wall_seconds()},
                               {"curve", curve},
                               {"errors", errors}});
    }
    if (!method.error().empty())
      entry["error"] = method.error();
    else if (entry["runs"].empty() && !failed.empty())
      entry["error"] = "every run failed: " + failed[0]["error"].get<std::string>();
    if (!failed.empty()) entry["failed_runs"] = failed;
    methods.push_back(entry);
  }
  index["methods"] = methods;
  std::string text = index.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  write_bytes(dir / "batch.json", text);
}

}  // namespace penumbra::farm
