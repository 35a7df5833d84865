#include "server/store.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <stdexcept>

namespace penumbra::farm {

namespace {

const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS scenes (hash TEXT PRIMARY KEY, package BLOB NOT NULL);
CREATE TABLE IF NOT EXISTS scene_chunks (
  hash TEXT PRIMARY KEY, data BLOB NOT NULL, added_ms INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS jobs (
  id INTEGER PRIMARY KEY AUTOINCREMENT, spec BLOB NOT NULL, priority INTEGER NOT NULL,
  state INTEGER NOT NULL, error TEXT NOT NULL, submitted_ms INTEGER NOT NULL,
  started_ms INTEGER NOT NULL, finished_ms INTEGER NOT NULL, blocks_opened INTEGER NOT NULL,
  blocks_sealed INTEGER NOT NULL, compute_seconds REAL NOT NULL, final_errors BLOB NOT NULL,
  result BLOB);
CREATE TABLE IF NOT EXISTS task_results (
  job_id INTEGER NOT NULL, task_index INTEGER NOT NULL, tile BLOB NOT NULL,
  compute_seconds REAL NOT NULL, PRIMARY KEY (job_id, task_index));
CREATE TABLE IF NOT EXISTS tiles (
  job_id INTEGER NOT NULL, tile_index INTEGER NOT NULL, sums BLOB NOT NULL,
  PRIMARY KEY (job_id, tile_index));
CREATE TABLE IF NOT EXISTS curve (
  job_id INTEGER NOT NULL, passes INTEGER NOT NULL, compute_seconds REAL NOT NULL,
  wall_seconds REAL NOT NULL, mrse REAL NOT NULL, PRIMARY KEY (job_id, passes));
CREATE TABLE IF NOT EXISTS curve_regions (
  job_id INTEGER NOT NULL, passes INTEGER NOT NULL, region TEXT NOT NULL, mrse REAL NOT NULL,
  PRIMARY KEY (job_id, passes, region));
)sql";

}  // namespace

// A prepared statement with positional binding (1-based) and column access (0-based).
class Store::Statement {
 public:
  Statement(Store& store, const char* sql) : store_(store) {
    int code = sqlite3_prepare_v2(store.db_, sql, -1, &statement_, nullptr);
    if (code != SQLITE_OK) store_.throw_error(code, sql);
  }
  ~Statement() { sqlite3_finalize(statement_); }
  Statement& bind(int index, int64_t value) {
    sqlite3_bind_int64(statement_, index, value);
    return *this;
  }
  Statement& bind(int index, double value) {
    sqlite3_bind_double(statement_, index, value);
    return *this;
  }
  Statement& bind_text(int index, const std::string& value) {
    sqlite3_bind_text(statement_, index, value.data(), int(value.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Statement& bind_blob(int index, const std::string& value) {
    sqlite3_bind_blob64(statement_, index, value.data(), value.size(), SQLITE_TRANSIENT);
    return *this;
  }
  // True while a row is available.
  bool step() {
    int code = sqlite3_step(statement_);
    if (code == SQLITE_ROW) return true;
    if (code == SQLITE_DONE) return false;
    store_.throw_error(code, sqlite3_sql(statement_));
  }
  void run() {
    while (step()) {
    }
  }
  void reset() {
    sqlite3_reset(statement_);
    sqlite3_clear_bindings(statement_);
  }
  int64_t integer(int column) { return sqlite3_column_int64(statement_, column); }
  double real(int column) { return sqlite3_column_double(statement_, column); }
  std::string blob(int column) {
    const void* data = sqlite3_column_blob(statement_, column);
    int size = sqlite3_column_bytes(statement_, column);
    return data ? std::string(static_cast<const char*>(data), size_t(size)) : std::string();
  }
  bool is_null(int column) { return sqlite3_column_type(statement_, column) == SQLITE_NULL; }

 private:
  Store& store_;
  sqlite3_stmt* statement_ = nullptr;
};

// BEGIN IMMEDIATE ... COMMIT; rolls back when destroyed without commit().
class Store::Transaction {
 public:
  explicit Transaction(Store& store) : store_(store) { store_.execute("BEGIN IMMEDIATE"); }
  ~Transaction() {
    if (!committed_) sqlite3_exec(store_.db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    store_.execute("COMMIT");
    committed_ = true;
  }

 private:
  Store& store_;
  bool committed_ = false;
};

Store::Store(const std::string& data_dir, StoreOptions options)
    : data_dir_(data_dir), options_(options) {
  std::error_code error;
  std::filesystem::create_directories(data_dir, error);
  path_ = (std::filesystem::path(data_dir) / "penumbra.sqlite").string();
  reserve_path_ = (std::filesystem::path(data_dir) / "penumbra.reserve").string();
  if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw std::runtime_error("cannot open " + path_ + ": " + message);
  }
  sqlite3_busy_timeout(db_, 10000);
  execute("PRAGMA journal_mode=WAL");
  execute("PRAGMA synchronous=FULL");
  // Debian builds SQLite with secure deletion on: every deleted task result (hundreds of KB
  // each) would be overwritten with zeros, as many bytes written again as were stored. FAST
  // zeroes only what is written anyway.
  execute("PRAGMA secure_delete=FAST");
  execute(kSchema);
  std::lock_guard lock(reserve_mutex_);
  if (!make_reserve())
    spdlog::warn("store: no room for the {} byte reserve in {}: the disk is nearly full",
                 options_.reserve_bytes, data_dir_);
}

Store::~Store() {
  sqlite3_close(db_);
}

void Store::execute(const char* sql) {
  int code = sqlite3_exec(db_, sql, nullptr, nullptr, nullptr);
  if (code != SQLITE_OK) throw_error(code, sql);
}

void Store::throw_error(int code, const std::string& context) {
  std::string message = sqlite3_errmsg(db_);
  int primary = code & 0xff;
  int system_error = primary == SQLITE_IOERR ? sqlite3_system_errno(db_) : 0;
  if (primary == SQLITE_FULL || system_error == ENOSPC || system_error == EDQUOT)
    throw FarmError(FarmErrorCode::ResourceExhausted,
                    "disk full: no space left on the coordinator's data disk (" + data_dir_ +
                        "); sqlite: " + message);
  std::string statement = context.substr(0, 120);
  throw std::runtime_error("sqlite (" + path_ + "): " + message +
                           (statement.empty() ? "" : " in: " + statement));
}

// Called with reserve_mutex_ held.
bool Store::make_reserve() {
  if (options_.reserve_bytes == 0) return true;
  struct stat info {};
  if (::stat(reserve_path_.c_str(), &info) == 0 && uint64_t(info.st_size) >= options_.reserve_bytes)
    return true;
  int fd = ::open(reserve_path_.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) return false;
  int error = ::posix_fallocate(fd, 0, off_t(options_.reserve_bytes));
  ::close(fd);
  if (error != 0) {
    ::unlink(reserve_path_.c_str());
    return false;
  }
  spdlog::info("store: reserve of {} bytes in place ({})", options_.reserve_bytes, reserve_path_);
  return true;
}

bool Store::spend_reserve() {
  std::lock_guard lock(reserve_mutex_);
  if (::unlink(reserve_path_.c_str()) != 0) return false;
  spdlog::warn(
      "store: the data disk is full; the reserve is released so that running jobs can "
      "finish, and new jobs are refused until space returns");
  return true;
}

bool Store::has_reserve() {
  std::lock_guard lock(reserve_mutex_);
  return options_.reserve_bytes == 0 || ::access(reserve_path_.c_str(), F_OK) == 0;
}

void Store::require_space_for_new_work(uint64_t bytes) {
  std::lock_guard lock(reserve_mutex_);
  bool reserve = make_reserve();
  struct statvfs info {};
  if (::statvfs(data_dir_.c_str(), &info) == 0) {
    uint64_t free_bytes = uint64_t(info.f_bavail) * uint64_t(info.f_frsize);
    if (free_bytes < options_.min_free_bytes + bytes)
      throw FarmError(FarmErrorCode::ResourceExhausted,
                      "disk full: " + std::to_string(free_bytes) +
                          " bytes free on the coordinator's data disk (" + data_dir_ +
                          "), new work needs " + std::to_string(options_.min_free_bytes + bytes) +
                          "; no new jobs until space is freed");
  }
  if (!reserve)
    throw FarmError(FarmErrorCode::ResourceExhausted,
                    "disk full: no room for the " + std::to_string(options_.reserve_bytes) +
                        " byte reserve on the coordinator's data disk (" + data_dir_ +
                        "); no new jobs until space is freed");
}

template <typename Write>
void Store::write_progress(Write&& write) {
  try {
    write();
    return;
  } catch (const FarmError& error) {
    if (error.code() != FarmErrorCode::ResourceExhausted || !spend_reserve()) throw;
  }
  write();
}

void Store::put_scene(const std::string& hash, const std::string& package) {
  require_space_for_new_work(package.size());
  std::lock_guard lock(mutex_);
  Statement(*this, "INSERT OR IGNORE INTO scenes (hash, package) VALUES (?, ?)")
      .bind_text(1, hash)
      .bind_blob(2, package)
      .run();
}

std::optional<std::string> Store::scene(const std::string& hash) {
  std::lock_guard lock(mutex_);
  Statement statement(*this, "SELECT package FROM scenes WHERE hash = ?");
  statement.bind_text(1, hash);
  if (!statement.step()) return std::nullopt;
  return statement.blob(0);
}

bool Store::has_scene(const std::string& hash) {
  std::lock_guard lock(mutex_);
  Statement statement(*this, "SELECT 1 FROM scenes WHERE hash = ?");
  statement.bind_text(1, hash);
  return statement.step();
}

void Store::put_scene_chunk(const std::string& hash, const std::string& data, int64_t unix_ms) {
  require_space_for_new_work(data.size());
  std::lock_guard lock(mutex_);
  Statement(*this, "INSERT OR IGNORE INTO scene_chunks (hash, data, added_ms) VALUES (?, ?, ?)")
      .bind_text(1, hash)
      .bind_blob(2, data)
      .bind(3, unix_ms)
      .run();
}

bool Store::has_scene_chunk(const std::string& hash) {
  std::lock_guard lock(mutex_);
  Statement statement(*this, "SELECT 1 FROM scene_chunks WHERE hash = ?");
  statement.bind_text(1, hash);
  return statement.step();
}

std::optional<std::string> Store::scene_chunk(const std::string& hash) {
  std::lock_guard lock(mutex_);
  Statement statement(*this, "SELECT data FROM scene_chunks WHERE hash = ?");
  statement.bind_text(1, hash);
  if (!statement.step()) return std::nullopt;
  return statement.blob(0);
}

void Store::put_scene_from_chunks(const std::string& hash, const std::string& package,
                                  const std::vector<std::string>& chunk_hashes) {
  require_space_for_new_work(package.size());
  std::lock_guard lock(mutex_);
  Transaction transaction(*this);
  Statement(*this, "INSERT OR IGNORE INTO scenes (hash, package) VALUES (?, ?)")
      .bind_text(1, hash)
      .bind_blob(2, package)
      .run();
  Statement remove(*this, "DELETE FROM scene_chunks WHERE hash = ?");
  for (const std::string& chunk : chunk_hashes) {
    remove.bind_text(1, chunk).run();
    remove.reset();
  }
  transaction.commit();
}

size_t Store::drop_scene_chunks_before(int64_t unix_ms) {
  std::lock_guard lock(mutex_);
  Statement(*this, "DELETE FROM scene_chunks WHERE added_ms < ?").bind(1, unix_ms).run();
  return size_t(sqlite3_changes(db_));
}

uint64_t Store::add_job(const JobRecord& job) {
  require_space_for_new_work(job.spec.size());
  std::lock_guard lock(mutex_);
  Statement(*this,
            "INSERT INTO jobs (spec, priority, state, error, submitted_ms, started_ms, "
            "finished_ms, blocks_opened, blocks_sealed, compute_seconds, final_errors) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)")
      .bind_blob(1, job.spec)
      .bind(2, int64_t(job.priority))
      .bind(3, int64_t(job.state))
      .bind_text(4, job.error)
      .bind(5, job.submitted_unix_ms)
      .bind(6, job.started_unix_ms)
      .bind(7, job.finished_unix_ms)
      .bind(8, int64_t(job.blocks_opened))
      .bind(9, int64_t(job.blocks_sealed))
      .bind(10, job.compute_seconds)
      .bind_blob(11, job.final_errors)
      .run();
  return uint64_t(sqlite3_last_insert_rowid(db_));
}

void Store::write_job_spec(const JobRecord& job) {
  Statement(*this, "UPDATE jobs SET spec = ? WHERE id = ?")
      .bind_blob(1, job.spec)
      .bind(2, int64_t(job.id))
      .run();
}

void Store::write_job_fields(const JobRecord& job) {
  Statement(*this,
            "UPDATE jobs SET state = ?, error = ?, started_ms = ?, finished_ms = ?, "
            "blocks_opened = ?, blocks_sealed = ?, compute_seconds = ?, final_errors = ? "
            "WHERE id = ?")
      .bind(1, int64_t(job.state))
      .bind_text(2, job.error)
      .bind(3, job.started_unix_ms)
      .bind(4, job.finished_unix_ms)
      .bind(5, int64_t(job.blocks_opened))
      .bind(6, int64_t(job.blocks_sealed))
      .bind(7, job.compute_seconds)
      .bind_blob(8, job.final_errors)
      .bind(9, int64_t(job.id))
      .run();
}

void Store::update_job(const JobRecord& job) {
  std::lock_guard lock(mutex_);
  write_progress([&] { write_job_fields(job); });
}

void Store::update_job_spec(const JobRecord& job) {
  std::lock_guard lock(mutex_);
  write_progress([&] {
    Transaction transaction(*this);
    write_job_spec(job);
    write_job_fields(job);
    transaction.commit();
  });
}

std::vector<JobRecord> Store::jobs() {
  std::lock_guard lock(mutex_);
  Statement statement(*this,
                      "SELECT id, spec, priority, state, error, submitted_ms, started_ms, "
                      "finished_ms, blocks_opened, blocks_sealed, compute_seconds, final_errors "
                      "FROM jobs ORDER BY id");
  std::vector<JobRecord> jobs;
  while (statement.step()) {
    JobRecord job;
    job.id = uint64_t(statement.integer(0));
    job.spec = statement.blob(1);
    job.priority = int(statement.integer(2));
    job.state = int(statement.integer(3));
    job.error = statement.blob(4);
    job.submitted_unix_ms = statement.integer(5);
    job.started_unix_ms = statement.integer(6);
    job.finished_unix_ms = statement.integer(7);
    job.blocks_opened = uint32_t(statement.integer(8));
    job.blocks_sealed = uint32_t(statement.integer(9));
    job.compute_seconds = statement.real(10);
    job.final_errors = statement.blob(11);
    jobs.push_back(std::move(job));
  }
  return jobs;
}

void Store::add_task_result(uint64_t job_id, const TaskResultRecord& result) {
  std::unique_lock lock(group_mutex_);
  group_queue_.push_back({job_id, result});
  const uint64_t ticket = ++group_enqueued_;
  while (group_committed_ < ticket) {
    if (group_writing_) {
      group_done_.wait(lock);
      continue;
    }
    // This caller leads: it writes everything queued so far in one transaction.
    group_writing_ = true;
    std::vector<QueuedResult> batch;
    batch.swap(group_queue_);
    const uint64_t first = group_committed_ + 1, last = group_enqueued_;
    lock.unlock();
    std::exception_ptr error;
    try {
      std::lock_guard connection(mutex_);
      write_progress([&] {
        Transaction transaction(*this);
        Statement insert(*this,
                         "INSERT OR REPLACE INTO task_results (job_id, task_index, tile, "
                         "compute_seconds) VALUES (?, ?, ?, ?)");
        for (const QueuedResult& queued : batch) {
          insert.bind(1, int64_t(queued.job_id))
              .bind(2, int64_t(queued.result.task_index))
              .bind_blob(3, queued.result.tile)
              .bind(4, queued.result.compute_seconds)
              .run();
          insert.reset();
        }
        transaction.commit();
      });
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error) {
      group_failures_.push_back({first, last, error});
      if (group_failures_.size() > 64) group_failures_.erase(group_failures_.begin());
    }
    group_committed_ = last;
    group_writing_ = false;
    group_done_.notify_all();
  }
  for (const FailedBatch& failed : group_failures_)
    if (ticket >= failed.first_ticket && ticket <= failed.last_ticket)
      std::rethrow_exception(failed.error);
}

std::vector<TaskResultRecord> Store::task_results(uint64_t job_id) {
  std::lock_guard lock(mutex_);
  Statement statement(*this,
                      "SELECT task_index, tile, compute_seconds FROM task_results "
                      "WHERE job_id = ? ORDER BY task_index");
  statement.bind(1, int64_t(job_id));
  std::vector<TaskResultRecord> results;
  while (statement.step())
    results.push_back({uint64_t(statement.integer(0)), statement.blob(1), statement.real(2)});
  return results;
}

void Store::seal_block(const JobRecord& job, const std::map<uint32_t, std::string>& tiles,
                       uint64_t first_task, uint64_t end_task,
                       const std::optional<CurvePoint>& point) {
  std::lock_guard lock(mutex_);
  write_progress([&] {
    Transaction transaction(*this);
    {
      Statement insert(*this,
                       "INSERT OR REPLACE INTO tiles (job_id, tile_index, sums) VALUES (?, ?, ?)");
      for (const auto& [tile_index, sums] : tiles) {
        insert.bind(1, int64_t(job.id)).bind(2, int64_t(tile_index)).bind_blob(3, sums).run();
        insert.reset();
      }
    }
    Statement(*this,
              "DELETE FROM task_results WHERE job_id = ? AND task_index >= ? AND task_index < ?")
        .bind(1, int64_t(job.id))
        .bind(2, int64_t(first_task))
        .bind(3, int64_t(end_task))
        .run();
    if (point) {
      Statement(
          *this,
          "INSERT OR REPLACE INTO curve (job_id, passes, compute_seconds, wall_seconds, mrse) "
          "VALUES (?, ?, ?, ?, ?)")
          .bind(1, int64_t(job.id))
          .bind(2, int64_t(point->passes))
          .bind(3, point->compute_seconds)
          .bind(4, point->wall_seconds)
          .bind(5, point->mrse)
          .run();
      Statement insert(*this,
                       "INSERT OR REPLACE INTO curve_regions (job_id, passes, region, mrse) "
                       "VALUES (?, ?, ?, ?)");
      for (const auto& [region, mrse] : point->regions) {
        insert.bind(1, int64_t(job.id))
            .bind(2, int64_t(point->passes))
            .bind_text(3, region)
            .bind(4, mrse)
            .run();
        insert.reset();
      }
    }
    write_job_fields(job);
    transaction.commit();
  });
}

std::map<uint32_t, std::string> Store::tiles(uint64_t job_id) {
  std::lock_guard lock(mutex_);
  Statement statement(*this, "SELECT tile_index, sums FROM tiles WHERE job_id = ?");
  statement.bind(1, int64_t(job_id));
  std::map<uint32_t, std::string> tiles;
  while (statement.step()) tiles[uint32_t(statement.integer(0))] = statement.blob(1);
  return tiles;
}

std::vector<CurvePoint> Store::curve(uint64_t job_id) {
  std::lock_guard lock(mutex_);
  Statement statement(*this,
                      "SELECT passes, compute_seconds, wall_seconds, mrse FROM curve "
                      "WHERE job_id = ? ORDER BY passes");
  statement.bind(1, int64_t(job_id));
  std::vector<CurvePoint> points;
  while (statement.step())
    points.push_back({uint32_t(statement.integer(0)),
                      statement.real(1),
                      statement.real(2),
                      statement.real(3),
                      {}});
  Statement regions(*this,
                    "SELECT passes, region, mrse FROM curve_regions WHERE job_id = ? "
                    "ORDER BY passes, region");
  regions.bind(1, int64_t(job_id));
  size_t at = 0;
  while (regions.step()) {
    const uint32_t passes = uint32_t(regions.integer(0));
    while (at < points.size() && points[at].passes < passes) ++at;
    if (at < points.size() && points[at].passes == passes)
      points[at].regions.emplace_back(regions.blob(1), regions.real(2));
  }
  return points;
}

void Store::finish_job(const JobRecord& job, const std::string& exr) {
  std::lock_guard lock(mutex_);
  write_progress([&] {
    Transaction transaction(*this);
    Statement(*this, "UPDATE jobs SET result = ? WHERE id = ?")
        .bind_blob(1, exr)
        .bind(2, int64_t(job.id))
        .run();
    write_job_fields(job);
    transaction.commit();
  });
}

std::optional<std::string> Store::result(uint64_t job_id) {
  std::lock_guard lock(mutex_);
  Statement statement(*this, "SELECT result FROM jobs WHERE id = ?");
  statement.bind(1, int64_t(job_id));
  if (!statement.step() || statement.is_null(0)) return std::nullopt;
  return statement.blob(0);
}

void Store::cancel_job(const JobRecord& job, const std::optional<std::string>& exr) {
  std::lock_guard lock(mutex_);
  write_progress([&] {
    Transaction transaction(*this);
    write_job_spec(job);
    if (exr)
      Statement(*this, "UPDATE jobs SET result = ? WHERE id = ?")
          .bind_blob(1, *exr)
          .bind(2, int64_t(job.id))
          .run();
    Statement(*this, "DELETE FROM task_results WHERE job_id = ?").bind(1, int64_t(job.id)).run();
    Statement(*this, "DELETE FROM tiles WHERE job_id = ?").bind(1, int64_t(job.id)).run();
    write_job_fields(job);
    transaction.commit();
  });
}

void Store::drop_work(const JobRecord& job) {
  std::lock_guard lock(mutex_);
  write_progress([&] {
    Transaction transaction(*this);
    Statement(*this, "DELETE FROM task_results WHERE job_id = ?").bind(1, int64_t(job.id)).run();
    Statement(*this, "DELETE FROM tiles WHERE job_id = ?").bind(1, int64_t(job.id)).run();
    write_job_fields(job);
    transaction.commit();
  });
}

}  // namespace penumbra::farm
