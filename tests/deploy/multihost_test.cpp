// The farm across "hosts": the coordinator and three workers each in its own network namespace,
// joined by a Linux bridge (10.x addresses; the test process is the client, on the bridge's
// address). A job completes bit-identical to a local render, every worker takes part, and the
// throughput with 1, 2 and 3 single-thread workers is measured and reported. Needs root (ip
// netns); skipped otherwise. Namespaces, links and processes are removed even when it fails.
#include <gtest/gtest.h>

#include <optional>

#include "proto/support/batch_client.h"
#include "tests/deploy/deploy_test_support.h"

namespace penumbra::farm::testing {
namespace {

const char* kIp = "/usr/sbin/ip";

bool sh(const std::string& command) {
  return run_command(command).exit_code == 0;
}

void must(const std::string& command) {
  CommandResult result = run_command(command);
  if (result.exit_code != 0) throw std::runtime_error(command + ": " + result.output);
}

// A bridge, one namespace per host with a veth into the bridge, and an address on the bridge for
// the test process. Everything is named after the test's pid (parallel runs do not collide).
class NetworkLab {
 public:
  NetworkLab(const std::vector<std::string>& hosts) {
    int pid = ::getpid();
    tag_ = "pd" + std::to_string(pid % 100000);
    subnet_ = "10." + std::to_string(200 + pid % 50) + "." + std::to_string((pid / 50) % 250) + ".";
    bridge_ = tag_ + "br";
    remove();
    try {
      must(std::string(kIp) + " link add " + bridge_ + " type bridge");
      must(std::string(kIp) + " addr add " + subnet_ + "254/24 dev " + bridge_);
      must(std::string(kIp) + " link set " + bridge_ + " up");
      for (size_t i = 0; i < hosts.size(); ++i) {
        std::string ns = tag_ + "-" + hosts[i];
        std::string outside = tag_ + "v" + std::to_string(i);
        std::string address = subnet_ + std::to_string(i + 1);
        must(std::string(kIp) + " netns add " + ns);
        namespaces_.push_back(ns);
        must(std::string(kIp) + " link add " + outside + " type veth peer name eth0 netns " + ns);
        must(std::string(kIp) + " link set " + outside + " master " + bridge_ + " up");
        must(std::string(kIp) + " -n " + ns + " addr add " + address + "/24 dev eth0");
        must(std::string(kIp) + " -n " + ns + " link set eth0 up");
        must(std::string(kIp) + " -n " + ns + " link set lo up");
        addresses_[hosts[i]] = address;
        namespace_of_[hosts[i]] = ns;
      }
    } catch (...) {
      remove();
      throw;
    }
  }
  ~NetworkLab() { remove(); }
  NetworkLab(const NetworkLab&) = delete;
  NetworkLab& operator=(const NetworkLab&) = delete;

  const std::string& address(const std::string& host) { return addresses_.at(host); }
  // argv running `arguments` inside the host's namespace (ip netns exec execs it: same pid).
  std::vector<std::string> on(const std::string& host, std::vector<std::string> arguments) {
    arguments.insert(arguments.begin(), {kIp, "netns", "exec", namespace_of_.at(host)});
    return arguments;
  }

 private:
  void remove() {
    // Deleting a namespace deletes its veth end, and with it the pair.
    CommandResult list = run_command(std::string(kIp) + " netns list");
    std::istringstream lines(list.output);
    for (std::string line; std::getline(lines, line);) {
      std::string name = line.substr(0, line.find(' '));
      if (name.rfind(tag_ + "-", 0) == 0) sh(std::string(kIp) + " netns delete " + name);
    }
    sh(std::string(kIp) + " link delete " + bridge_ + " 2>/dev/null");
    namespaces_.clear();
  }

  std::string tag_, subnet_, bridge_;
  std::vector<std::string> namespaces_;
  std::map<std::string, std::string> addresses_, namespace_of_;
};

std::unique_ptr<ChildProcess> start_worker_on(NetworkLab& lab, const std::string& host,
                                              const std::string& coordinator,
                                              const std::filesystem::path& dir) {
  return std::make_unique<ChildProcess>(
      lab.on(host, {binary("worker/penumbra-worker"), "--coordinator", coordinator, "--threads",
                    "1", "--cache-dir", (dir / ("cache-" + host)).string(), "--name", host}),
      (dir / (host + ".log")).string());
}

size_t alive_workers(FarmClient& client) {
  size_t alive = 0;
  for (const v1::WorkerInfo& worker : client.workers()) alive += worker.alive();
  return alive;
}

TEST(MultiHost, CoordinatorAndThreeWorkersInNetworkNamespaces) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root for ip netns";
  if (!std::filesystem::exists(kIp)) GTEST_SKIP() << "no " << kIp;
  auto started = std::chrono::steady_clock::now();
  auto dir = fresh_directory("multihost");
  std::optional<NetworkLab> lab;
  try {
    lab.emplace(std::vector<std::string>{"coord", "w1", "w2", "w3"});
  } catch (const std::exception& error) {
    GTEST_SKIP() << "cannot build the namespaces here: " << error.what();
  }
  const std::string coordinator_address = lab->address("coord") + ":7420";

  auto port_file = dir / "port";
  ChildProcess coordinator(
      lab->on("coord", {binary("server/penumbra-coordinator"), "--listen", coordinator_address,
                        "--data-dir", (dir / "state").string(), "--port-file", port_file.string(),
                        "--lease-seconds", "5"}),
      (dir / "coordinator.log").string());
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!std::filesystem::exists(port_file)) {
    ASSERT_TRUE(coordinator.running()) << "coordinator exited; see " << dir / "coordinator.log";
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "coordinator did not start";
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // The client is this process, on the bridge: it reaches the coordinator's host over the bridge.
  FarmClient client(coordinator_address);
  std::string scene = write_scene(dir, 128, 96);

  // Throughput with 1, 2 and 3 single-thread workers (each on its own "host").
  const std::vector<std::string> hosts = {"w1", "w2", "w3"};
  std::vector<std::unique_ptr<ChildProcess>> workers;
  std::vector<double> tasks_per_second;
  for (size_t count = 1; count <= hosts.size(); ++count) {
    workers.push_back(start_worker_on(*lab, hosts[count - 1], coordinator_address, dir));
    auto registered_by = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (alive_workers(client) < count) {
      ASSERT_LT(std::chrono::steady_clock::now(), registered_by)
          << "worker on " << hosts[count - 1] << " did not register; see " << dir;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    uint64_t seed = 100 + count;
    v1::JobSpec spec = job_spec(scene, "sa", 256, seed, 32, 32);
    auto submitted = std::chrono::steady_clock::now();
    std::string job = client.submit(spec).job_id();
    v1::JobStatus done = client.wait(job, std::chrono::seconds(60));
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - submitted).count();
    ASSERT_EQ(done.state(), v1::JOB_STATE_DONE) << done.error();
    tasks_per_second.push_back(double(done.tasks_total()) / seconds);
    std::printf("multihost: %zu worker(s): %llu tasks in %.2f s = %.1f tasks/s (%.2f compute s)\n",
                count, (unsigned long long)done.tasks_total(), seconds, tasks_per_second.back(),
                done.compute_seconds());
    RecordProperty("tasks_per_second_" + std::to_string(count) + "_workers",
                   std::to_string(tasks_per_second.back()));
    if (count == hosts.size()) {
      // The last job: every worker took part and the image is the local render's, bit for bit.
      expect_bit_identical(client, job, scene, "sa", 256, seed);
      for (const v1::WorkerInfo& worker : client.workers())
        EXPECT_GT(worker.tasks_completed(), 0u) << worker.name();
    }
  }
  // More workers never make it much slower (on a 2-core machine 3 single-thread workers
  // saturate at about 2x; the figures are printed above for the capacity notes).
  EXPECT_GT(tasks_per_second[1], 0.8 * tasks_per_second[0]);

  // A batch across the hosts: a small auto reference, two methods at two sample counts; every
  // run ends with its errors against the reference.
  {
    std::string spec_text = R"({"format": "penumbra/batch@1", "name": "multihost",
        "scene": ")" + scene +
                            R"(", "methods": ["sa", "bsdf+sa"], "budget": {"spp": [4, 8]},
        "reference": {"method": "bsdf+sa", "spp": 32}, "seed": 3, "repeats": 1})";
    BatchClient batches(coordinator_address);
    auto request = make_batch_request_from_text(spec_text, "multihost-batch.json", dir.string(),
                                                [](const std::string& name) { return name; });
    std::string batch = batches.submit(request).batch_id();
    v1::BatchStatus done = batches.watch(batch, {}, std::chrono::seconds(60));
    ASSERT_EQ(done.state(), v1::BATCH_STATE_DONE) << done.error();
    ASSERT_EQ(done.methods_size(), 2);
    for (const v1::BatchMethodStatus& method : done.methods()) {
      EXPECT_TRUE(method.error().empty()) << method.label() << ": " << method.error();
      ASSERT_EQ(method.runs_size(), 2) << method.label();
      for (const v1::BatchRun& run : method.runs()) {
        EXPECT_EQ(run.job().state(), v1::JOB_STATE_DONE) << method.label() << " " << run.job_id();
        EXPECT_EQ(run.job().passes_complete(), run.spp_planned()) << method.label();
        EXPECT_TRUE(run.job().has_mrse()) << method.label();
      }
    }
    std::printf("multihost: batch %s done in %.2f s wall (%u jobs)\n", batch.c_str(),
                done.wall_seconds(), done.jobs_total());
  }

  for (auto& worker : workers) worker->signal(SIGTERM);
  for (auto& worker : workers) worker->wait_exit(std::chrono::seconds(30));
  coordinator.signal(SIGTERM);
  coordinator.wait_exit(std::chrono::seconds(30));
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(90));
  lab.reset();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm::testing
