// Fault: the coordinator's data disk fills up (a small tmpfs mounted for the test, filled by a
// file). The store (server/store.h) reports a full disk as FarmError(ResourceExhausted,
// "disk full: ..."), keeps a reserve so that running jobs still finish, and refuses new jobs
// until space returns. Checked at two levels:
//  - the Store alone: writes on a full disk throw "disk full" and leave the database as it was;
//  - a coordinator process: a job running when the disk fills finishes; submissions get
//    RESOURCE_EXHAUSTED with "disk full" while it is full and succeed once the file is removed;
//    the coordinator never stops serving; after a SIGKILL and restart the SQLite file passes
//    `PRAGMA integrity_check` and every job's EXR is bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/mount.h>

#include "fault_support.h"
#include "server/store.h"

namespace penumbra::farm::fault {
namespace {

[[maybe_unused]] auto* const table = ::testing::AddGlobalTestEnvironment(new FaultTableEnvironment);

// A tmpfs of `mib` MiB mounted on `dir` for the life of the object.
class SmallDisk {
 public:
  SmallDisk(const std::filesystem::path& dir, int mib) : dir_(dir) {
    std::filesystem::create_directories(dir);
    std::string options = "size=" + std::to_string(mib) + "m";
    if (::mount("tmpfs", dir.c_str(), "tmpfs", 0, options.c_str()) != 0)
      throw std::runtime_error("cannot mount a tmpfs on " + dir.string());
  }
  ~SmallDisk() { ::umount2(dir_.c_str(), MNT_DETACH); }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;

  // Writes a file until the disk refuses more (ENOSPC); returns the bytes written.
  uint64_t fill(const std::string& name) {
    int fd = ::open((dir_ / name).c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) throw std::runtime_error("cannot create the filler file");
    std::string chunk(1 << 20, 'x');
    uint64_t written = 0;
    for (size_t size : {size_t(1) << 20, size_t(4096), size_t(1)}) {
      while (true) {
        ssize_t n = ::write(fd, chunk.data(), size);
        if (n <= 0) break;
        written += uint64_t(n);
      }
    }
    ::close(fd);
    return written;
  }
  void remove(const std::string& name) { std::filesystem::remove(dir_ / name); }

 private:
  std::filesystem::path dir_;
};

bool is_disk_full_error(const std::string& message) {
  return message.find("disk full") != std::string::npos ||
         message.find("no space") != std::string::npos;
}

std::string integrity_check(const std::filesystem::path& database) {
  sqlite3* db = nullptr;
  std::string result = "cannot open";
  if (sqlite3_open_v2(database.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &statement, nullptr) == SQLITE_OK &&
        sqlite3_step(statement) == SQLITE_ROW)
      result = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
    sqlite3_finalize(statement);
  }
  sqlite3_close(db);
  return result;
}

TEST(FaultDiskFull, StoreReportsAFullDiskAndRecovers) {
  if (::geteuid() != 0) GTEST_SKIP() << "fault test skipped: needs root to mount a tmpfs";
  auto dir = testing::fresh_directory("fault-store-full");
  SmallDisk disk(dir / "data", 4);
  StoreOptions options;
  options.reserve_bytes = 512 << 10;
  Store store((dir / "data").string(), options);
  EXPECT_TRUE(store.has_reserve());
  JobRecord job;
  job.spec = "spec";
  job.id = store.add_job(job);
  disk.fill("filler");
  // New work is refused with a clear error.
  try {
    store.add_job(job);
    ADD_FAILURE() << "a job was added on a full disk";
  } catch (const FarmError& error) {
    EXPECT_EQ(error.code(), FarmErrorCode::ResourceExhausted);
    EXPECT_TRUE(is_disk_full_error(error.what())) << error.what();
  }
  // Progress goes on, out of the reserve, until the reserve is spent too.
  const std::string tile(64 << 10, 't');
  uint64_t stored = 0;
  bool full = false;
  for (uint64_t task = 0; task < 200 && !full; ++task) {
    try {
      store.add_task_result(job.id, {task, tile, 0.5});
      ++stored;
    } catch (const FarmError& error) {
      EXPECT_EQ(error.code(), FarmErrorCode::ResourceExhausted);
      EXPECT_TRUE(is_disk_full_error(error.what())) << error.what();
      full = true;
    }
  }
  std::printf("task results stored after the disk filled: %llu of 64 KiB (reserve 512 KiB)\n",
              (unsigned long long)stored);
  EXPECT_TRUE(full) << "200 x 64 KiB fit on a full 4 MiB disk?";
  EXPECT_GE(stored, 4u) << "the reserve did not let progress go on";
  EXPECT_FALSE(store.has_reserve());
  // What was acknowledged is there; the failed write left nothing behind.
  EXPECT_EQ(store.task_results(job.id).size(), stored);
  // Space returns: new work is accepted again and the reserve is remade.
  disk.remove("filler");
  JobRecord second;
  second.spec = "second";
  EXPECT_EQ(store.add_job(second), job.id + 1);
  EXPECT_TRUE(store.has_reserve());
  store.add_task_result(job.id, {999, tile, 0.5});
  EXPECT_EQ(store.task_results(job.id).size(), stored + 1);
  EXPECT_EQ(integrity_check(dir / "data" / "penumbra.sqlite"), "ok");
}

TEST(FaultDiskFull, CoordinatorRefusesNewJobsFinishesRunningOnesAndRecovers) {
  if (::geteuid() != 0) GTEST_SKIP() << "fault test skipped: needs root to mount a tmpfs";
  auto dir = testing::fresh_directory("fault-disk-full");
  std::string scene = testing::write_scene(dir, 64, 64);
  auto data = dir / "data";
  SmallDisk disk(data, 24);
  testing::CoordinatorProcess coordinator(data, 0, {}, 1.0);
  const std::string address = coordinator.address();
  auto worker_a = testing::start_worker(address, dir, "a");
  auto worker_b = testing::start_worker(address, dir, "b");
  FarmClient client(address);

  // The running job: 16 tiles x 16 blocks of 64 passes. The disk fills once its first block is
  // sealed, with 15/16 of its work (about a second of one thread) still to come: it is still
  // running when the fill is over (ten milliseconds), however fast the machine. Its writes are
  // those of 16 blocks whatever their length, as many as the reserve was sized for.
  std::vector<SubmittedJob> jobs;
  SubmittedJob running{"", "sa", 1024, 41};
  running.id = client.submit(testing::job_spec(scene, "sa", 1024, 41, 16, 64)).job_id();
  jobs.push_back(running);
  testing::wait_until(client, running.id,
                      [](const v1::JobStatus& s) { return s.passes_complete() >= 64; });

  uint64_t filled = disk.fill("filler");
  v1::JobStatus at_fill = client.status(running.id);
  std::printf("disk filled with %.1f MiB; the running job at %u of %u passes\n",
              double(filled) / double(1 << 20), at_fill.passes_complete(), running.spp);
  ASSERT_FALSE(job_ended(at_fill.state()))
      << "the job ended before the disk was full: no running job met the full disk";
  int refusals = 0;
  for (int attempt = 0; attempt < 3; ++attempt) {
    try {
      client.submit(testing::job_spec(scene, "sa", 16, 42 + uint64_t(attempt)));
      ADD_FAILURE() << "a job was accepted on a full disk";
    } catch (const FarmCallError& error) {
      std::printf("submit on a full disk: %s: %s\n", status_code_name(error.code()).c_str(),
                  error.what());
      EXPECT_TRUE(error.code() == grpc::StatusCode::RESOURCE_EXHAUSTED ||
                  error.code() == grpc::StatusCode::UNAVAILABLE)
          << status_code_name(error.code());
      EXPECT_TRUE(is_disk_full_error(error.what())) << error.what();
      ++refusals;
    }
    std::this_thread::sleep_for(200ms);
  }
  // The running job finishes while the disk is full when the reserve covers its remaining
  // writes; when the reserve runs out first (how far the job got before the disk filled depends
  // on the machine's load), it waits, nothing lost, and finishes as soon as space returns. The
  // coordinator keeps serving meanwhile.
  v1::JobStatus status;
  bool finished_while_full = true;
  try {
    status = client.wait(running.id, 60s);
  } catch (const FarmCallError& error) {
    if (error.code() != grpc::StatusCode::DEADLINE_EXCEEDED) throw;
    finished_while_full = false;
  }
  EXPECT_TRUE(coordinator.process().running());
  EXPECT_FALSE(client.list().empty());

  // Space returns: the running job (if it waited) and new jobs complete.
  disk.remove("filler");
  if (!finished_while_full) {
    std::printf(
        "the reserve ran out before the running job ended: it finishes after space returns\n");
    status = client.wait(running.id, 60s);
  }
  EXPECT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  SubmittedJob after{"", "sa", 32, 43};
  after.id = client.submit(testing::job_spec(scene, "sa", 32, 43, 16, 4)).job_id();
  jobs.push_back(after);
  status = client.wait(after.id, 60s);
  EXPECT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();

  // No corrupt state: kill it, check the database, restart on it, compare the images.
  coordinator.kill();
  EXPECT_EQ(integrity_check(data / "penumbra.sqlite"), "ok");
  coordinator.restart();
  FaultRow row{"coordinator data disk full (tmpfs)", refusals};
  check_jobs(address, scene, jobs, row);
  record_fault_row(row);
  EXPECT_EQ(refusals, 3);
  EXPECT_EQ(row.lost_jobs, 0);
  EXPECT_EQ(row.mismatched_images, 0);
}

}  // namespace
}  // namespace penumbra::farm::fault
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
