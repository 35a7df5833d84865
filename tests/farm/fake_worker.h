#pragma once
// A fake worker for the coordinator's core (no gRPC, no renderer): it registers, leases tasks and
// completes them with synthetic tiles whose values depend only on pixel and pass, so the image a
// job assembles is known exactly (tests/farm/coordinator_test.cpp, tests/batch/
// calibrated_run_test.cpp).

#include <string>
#include <vector>

#include "core/render/tile.h"
#include "penumbra/version.h"
#include "server/coordinator.h"

namespace penumbra::farm::testing {

// The radiance the fake worker "renders" for pixel (x, y) in pass p (exactly representable).
inline Rgb fake_radiance(int x, int y, uint32_t pass) {
  return {double(x % 7) * 0.25 + pass * 0.5, double(y % 5) * 0.125, double((x + y + pass) % 3)};
}

// The task's tile: every pixel's samples of its passes.
inline TileAccumulator fake_render(const v1::Task& task) {
  TileRect rect{task.tile().x0(), task.tile().y0(), task.tile().x1(), task.tile().y1()};
  TileAccumulator tile(rect);
  for (int y = rect.y0; y < rect.y1; ++y)
    for (int x = rect.x0; x < rect.x1; ++x)
      for (uint32_t pass = task.pass_begin(); pass < task.pass_end(); ++pass)
        tile.add_sample(int64_t(y - rect.y0) * rect.width() + (x - rect.x0),
                        fake_radiance(x, y, pass));
  return tile;
}

// Registers a one-thread worker of this build; returns its id.
inline std::string register_fake_worker(Coordinator& coordinator, const std::string& name) {
  v1::RegisterRequest request;
  request.set_name(name);
  request.set_threads(1);
  request.set_build_flavour(kBuildFlavour);
  request.set_protocol_version(v1::PROTOCOL_VERSION_CURRENT);
  return coordinator.register_worker(request).worker_id();
}

inline std::vector<v1::Task> lease_tasks(Coordinator& coordinator, const std::string& worker,
                                         uint32_t max_tasks) {
  v1::LeaseTasksRequest request;
  request.set_worker_id(worker);
  request.set_max_tasks(max_tasks);
  auto response = coordinator.lease_tasks(request);
  return {response.tasks().begin(), response.tasks().end()};
}

// Completes the task with its fake tile and `seconds` of compute; the coordinator's answer.
inline bool complete_fake_task(Coordinator& coordinator, const std::string& worker,
                               const v1::Task& task, double seconds) {
  v1::CompleteTaskRequest request;
  request.set_worker_id(worker);
  request.set_job_id(task.job_id());
  request.set_task_index(task.task_index());
  request.set_attempt_token(task.attempt_token());
  request.set_tile(fake_render(task).serialize());
  request.set_compute_seconds(seconds);
  return coordinator.complete_task(request);
}

}  // namespace penumbra::farm::testing
