// Load: 20 concurrent clients submit 200 small jobs in all to one coordinator process with 4
// worker processes. Every job completes, bit-identical to a local render (none lost); the
// coordinator's peak resident memory (VmHWM in /proc/<pid>/status) stays under a generous
// bound, and the figure is printed.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <dirent.h>
#include <gtest/gtest.h>

#include <atomic>

#include "../fault/fault_support.h"

namespace penumbra::farm::fault {
namespace {

// The pid of the process whose command line holds `argument` (e.g. its unique data directory).
pid_t pid_with_argument(const std::string& argument) {
  DIR* proc = ::opendir("/proc");
  if (!proc) return -1;
  pid_t found = -1;
  while (dirent* entry = ::readdir(proc)) {
    char* end = nullptr;
    long pid = std::strtol(entry->d_name, &end, 10);
    if (*end != '\0' || pid <= 0) continue;
    std::ifstream file("/proc/" + std::string(entry->d_name) + "/cmdline");
    std::string cmdline((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    size_t start = 0;
    while (start < cmdline.size()) {
      size_t stop = cmdline.find('\0', start);
      if (stop == std::string::npos) stop = cmdline.size();
      if (cmdline.compare(start, stop - start, argument) == 0) found = pid_t(pid);
      start = stop + 1;
    }
    if (found > 0) break;
  }
  ::closedir(proc);
  return found;
}

// A field of /proc/<pid>/status in KiB (VmHWM: peak resident set, VmRSS: current).
long status_kib(pid_t pid, const std::string& field) {
  std::ifstream file("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(file, line))
    if (line.rfind(field + ":", 0) == 0)
      return std::strtol(line.c_str() + field.size() + 1, nullptr, 10);
  return -1;
}

TEST(Load, TwentyClientsTwoHundredJobsFourWorkers) {
  auto dir = testing::fresh_directory("load");
  std::string scene = testing::write_scene(dir, 32, 32);
  auto data = dir / "data";
  testing::CoordinatorProcess coordinator(data, 0, {}, 2.0);
  const pid_t pid = pid_with_argument(data.string());
  ASSERT_GT(pid, 0) << "cannot find the coordinator's process";
  const long rss_idle = status_kib(pid, "VmRSS");
  std::vector<std::unique_ptr<testing::ChildProcess>> workers;
  for (int w = 0; w < 4; ++w)
    workers.push_back(testing::start_worker(coordinator.address(), dir, "w" + std::to_string(w)));

  const int clients = 20, jobs_per_client = 10;
  std::vector<SubmittedJob> jobs(size_t(clients * jobs_per_client));
  std::atomic<int> submit_errors{0};
  auto start = Clock::now();
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      FarmClient client(coordinator.address());  // a channel of its own per client
      for (int j = 0; j < jobs_per_client; ++j) {
        SubmittedJob& job = jobs[size_t(c * jobs_per_client + j)];
        job.method = "sa";
        job.spp = 4 + 4 * uint32_t(j % 3);
        job.seed = uint64_t(c * 1000 + j);
        try {
          // One 32x32 tile, passes in blocks of 4: one to three tasks per job.
          job.id = client.submit(testing::job_spec(scene, job.method, job.spp, job.seed, 32, 4))
                       .job_id();
        } catch (const std::exception& error) {
          ++submit_errors;
          ADD_FAILURE() << "client " << c << " job " << j << ": " << error.what();
        }
      }
      // Each client watches its own jobs to the end, as `penumbra watch` would.
      for (int j = 0; j < jobs_per_client; ++j) {
        const SubmittedJob& job = jobs[size_t(c * jobs_per_client + j)];
        if (!job.id.empty()) client.wait(job.id, 120s);
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  const double wall = seconds_since(start);
  ASSERT_EQ(submit_errors.load(), 0);

  FaultRow row{"load: 20 clients, 200 jobs, 4 workers", 0};
  check_jobs(coordinator.address(), scene, jobs, row);
  const long peak = status_kib(pid, "VmHWM");
  const long rss = status_kib(pid, "VmRSS");
  std::printf(
      "200 jobs from 20 clients done in %.1f s (%.1f jobs/s); coordinator memory: idle "
      "%ld KiB, peak (VmHWM) %ld KiB, now %ld KiB\n",
      wall, 200.0 / wall, rss_idle, peak, rss);
  print_fault_table({row});
  EXPECT_EQ(row.lost_jobs, 0);
  EXPECT_EQ(row.mismatched_images, 0);
  ASSERT_GT(peak, 0);
  EXPECT_LT(peak, 512L * 1024) << "the coordinator's peak memory exceeds 512 MiB";
  EXPECT_TRUE(coordinator.process().running());
}

}  // namespace
}  // namespace penumbra::farm::fault
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
