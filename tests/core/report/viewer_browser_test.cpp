// The comparison viewer in a real browser: a batch report written from a small synthetic batch
// folder is loaded from disk in headless Chromium, driven through the DevTools protocol (over
// --remote-debugging-pipe: key presses and mouse moves as the browser's own input events), and
// what the canvas shows is read back and checked against the EXRs: the key flips the method,
// zoom is nearest neighbour, the crops show the same pixel, the exposure and the error views
// give the values computed here, the probe and the table's links work, and the page neither
// logs errors nor makes a request; the viewer without a reference (a farm job's) shows the image
// and its variance alone. Screenshots at two zoom levels are written for people.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "core/image/image.h"
#include "core/image/metrics.h"
#include "core/report/batch_figure.h"
#include "core/report/batch_report.h"
#include "core/report/comparison_viewer.h"

extern char** environ;

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

const char* kChromium = "/usr/bin/chromium";
constexpr int kWidth = 64, kHeight = 48;

fs::path output_dir() {
  fs::path dir = fs::path(PENUMBRA_BINARY_DIR) / "test-output" / "report" / "viewer";
  fs::create_directories(dir);
  return dir;
}

// Chromium with the DevTools protocol on file descriptors 3 (commands in) and 4 (replies and
// events out), messages separated by NUL bytes. Every wait has a deadline.
class Chromium {
 public:
  explicit Chromium(const fs::path& dir) {
    int in[2], out[2];
    if (pipe(in) != 0 || pipe(out) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], 3);
    posix_spawn_file_actions_adddup2(&actions, out[1], 4);
    const std::string log = (dir / "chromium.log").string();
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    const std::string profile = "--user-data-dir=" + (dir / "chromium-profile").string();
    std::vector<std::string> args = {kChromium,
                                     "--headless=new",
                                     "--no-sandbox",
                                     "--disable-gpu",
                                     "--no-first-run",
                                     "--no-default-browser-check",
                                     "--remote-debugging-pipe",
                                     "--window-size=1300,1000",
                                     profile,
                                     "about:blank"};
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, kChromium, &actions, nullptr, argv.data(), environ) != 0)
      throw std::runtime_error("cannot start chromium");
    posix_spawn_file_actions_destroy(&actions);
    close(in[0]);
    close(out[1]);
    to_browser_ = in[1];
    from_browser_ = out[0];
  }

  ~Chromium() {
    if (pid_ <= 0) return;
    try {
      send("Browser.close", json::object(), "");
    } catch (...) {
    }
    for (int i = 0; i < 50; ++i) {
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) {
        pid_ = 0;
        break;
      }
      usleep(100000);
    }
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(to_browser_);
    close(from_browser_);
  }

  // Sends a command and waits for its reply; throws with the protocol's error message.
  json call(const std::string& method, const json& params, const std::string& session) {
    int id = send(method, params, session);
    for (;;) {
      json message = next_message();
      if (message.value("id", -1) != id) {
        events_.push_back(std::move(message));
        continue;
      }
      if (message.contains("error"))
        throw std::runtime_error(method + ": " + message["error"].dump());
      return message.value("result", json::object());
    }
  }

  // Waits for an event of `method` (already received ones count).
  json wait_event(const std::string& method) {
    for (const json& event : events_)
      if (event.value("method", "") == method) return event;
    for (;;) {
      json message = next_message();
      events_.push_back(message);
      if (message.value("method", "") == method) return message;
    }
  }

  // Drains what arrived, without waiting.
  const std::vector<json>& events() {
    while (readable(0)) events_.push_back(next_message());
    return events_;
  }

  void set_deadline(Clock::time_point deadline) { deadline_ = deadline; }

 private:
  int send(const std::string& method, const json& params, const std::string& session) {
    json message = {{"id", next_id_}, {"method", method}, {"params", params}};
    if (!session.empty()) message["sessionId"] = session;
    std::string text = message.dump();
    text += '\0';
    for (size_t done = 0; done < text.size();) {
      ssize_t wrote = write(to_browser_, text.data() + done, text.size() - done);
      if (wrote <= 0) throw std::runtime_error("chromium closed its pipe");
      done += size_t(wrote);
    }
    return next_id_++;
  }

  bool readable(int timeout_ms) {
    pollfd fd{from_browser_, POLLIN, 0};
    return poll(&fd, 1, timeout_ms) > 0;
  }

  json next_message() {
    for (;;) {
      size_t end = buffer_.find('\0');
      if (end != std::string::npos) {
        json message = json::parse(buffer_.substr(0, end));
        buffer_.erase(0, end + 1);
        return message;
      }
      auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - Clock::now());
      if (left.count() <= 0 || !readable(int(left.count())))
        throw std::runtime_error("chromium did not answer in time");
      char chunk[65536];
      ssize_t got = read(from_browser_, chunk, sizeof chunk);
      if (got <= 0) throw std::runtime_error("chromium closed its pipe");
      buffer_.append(chunk, size_t(got));
    }
  }

  pid_t pid_ = 0;
  int to_browser_ = -1, from_browser_ = -1;
  int next_id_ = 1;
  std::string buffer_;
  std::vector<json> events_;
  Clock::time_point deadline_ = Clock::now() + std::chrono::seconds(20);
};

// One page of the browser, attached with a flat session.
class Page {
 public:
  explicit Page(Chromium& browser) : browser_(browser) {
    std::string target =
        browser.call("Target.createTarget", {{"url", "about:blank"}}, "")["targetId"];
    session_ = browser.call("Target.attachToTarget", {{"targetId", target}, {"flatten", true}},
                            "")["sessionId"];
    for (const char* domain : {"Page.enable", "Runtime.enable", "Network.enable"})
      call(domain, json::object());
    call("Emulation.setDeviceMetricsOverride",
         {{"width", 1300}, {"height", 1000}, {"deviceScaleFactor", 1}, {"mobile", false}});
  }

  json call(const std::string& method, const json& params) {
    return browser_.call(method, params, session_);
  }
  const std::string& session() const { return session_; }

  // Waits until the viewer of the page now loading has decoded its images (or failed).
  void wait_for_viewer(Clock::time_point deadline) {
    for (;;) {
      try {
        json state = eval(
            "(function(){var v=document.getElementById('viewer');return !!v&&(v.hasAttribute("
            "'data-ready')||v.hasAttribute('data-error'));})()");
        if (state.is_boolean() && state.get<bool>()) return;
      } catch (const std::runtime_error&) {
        // The document was replaced while the expression ran: ask the new one.
      }
      if (Clock::now() > deadline) throw std::runtime_error("the viewer did not get ready");
      usleep(20'000);
    }
  }

  // The value of a JavaScript expression (promises awaited).
  json eval(const std::string& expression) {
    json result =
        call("Runtime.evaluate",
             {{"expression", expression}, {"returnByValue", true}, {"awaitPromise", true}});
    if (result.contains("exceptionDetails"))
      throw std::runtime_error(expression + ": " + result["exceptionDetails"].dump());
    return result["result"].value("value", json());
  }

  void key(const std::string& key, const std::string& code, int key_code) {
    json down = {{"type", "keyDown"},
                 {"key", key},
                 {"code", code},
                 {"windowsVirtualKeyCode", key_code},
                 {"text", key}};
    call("Input.dispatchKeyEvent", down);
    call("Input.dispatchKeyEvent",
         {{"type", "keyUp"}, {"key", key}, {"code", code}, {"windowsVirtualKeyCode", key_code}});
  }

  std::string attribute(const std::string& name) {
    json value = eval("document.getElementById('viewer').getAttribute('" + name + "')");
    return value.is_string() ? value.get<std::string>() : "";
  }

  // RGB of a device pixel of a canvas (the main one, or crop `crop`).
  std::array<int, 3> pixel(int x, int y, int crop = -1) {
    std::string canvas = crop < 0 ? "document.querySelector('#viewer .pv-canvas')"
                                  : "document.querySelectorAll('#viewer .pv-crops canvas')[" +
                                        std::to_string(crop) + "]";
    json value = eval("Array.from(" + canvas + ".getContext('2d').getImageData(" +
                      std::to_string(x) + "," + std::to_string(y) + ",1,1).data)");
    return {value[0].get<int>(), value[1].get<int>(), value[2].get<int>()};
  }

  void screenshot(const fs::path& path) {
    json box = eval(
        "(function(){var r=document.getElementById('viewer').getBoundingClientRect();"
        "return [r.left+scrollX,r.top+scrollY,r.width,r.height];})()");
    json result = call(
        "Page.captureScreenshot",
        {{"format", "png"},
         {"captureBeyondViewport", true},
         {"clip",
          {{"x", box[0]}, {"y", box[1]}, {"width", box[2]}, {"height", box[3]}, {"scale", 1}}}});
    std::string encoded = result["data"];
    std::string bytes;
    uint32_t bits = 0;
    int count = 0;
    for (char c : encoded) {
      const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
      const char* at = std::strchr(alphabet, c);
      if (!at || c == '\0') continue;
      bits = bits << 6 | uint32_t(at - alphabet);
      if ((count += 6) >= 8) bytes += char((bits >> (count -= 8)) & 0xff);
    }
    std::ofstream(path, std::ios::binary) << bytes;
  }

 private:
  Chromium& browser_;
  std::string session_;
};

// A smooth reference with a dark band, and two methods: the reference plus noise of two sizes.
struct SyntheticBatch {
  fs::path dir;
  Image reference;
  std::vector<Image> methods;
  std::vector<Image> variances;  // the methods' variance layers
  std::vector<std::string> labels = {"low-noise", "high-noise"};
  Region region{10, 8, 30, 24};
};

SyntheticBatch write_synthetic_batch(const fs::path& dir) {
  SyntheticBatch batch;
  batch.dir = dir;
  fs::remove_all(dir);
  fs::create_directories(dir / "runs");
  batch.reference = Image(kWidth, kHeight);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      double band = (x > 20 && x < 28) ? 0.1 : 1.0;
      batch.reference.set(x, y, Rgb{0.2 + x / 40.0, 0.1 + y / 60.0, 0.3} * band);
    }
  Image variance(kWidth, kHeight);
  for (float& v : variance.rgb) v = 1e-6f;
  write_exr((dir / "reference.exr").string(), batch.reference, &variance, {});
  std::mt19937 random(5);
  json methods = json::array();
  for (size_t m = 0; m < batch.labels.size(); ++m) {
    std::normal_distribution<double> noise(0, m == 0 ? 0.05 : 0.3);
    Image image = batch.reference;
    for (float& v : image.rgb) v = float(std::max(0.0, v * (1 + noise(random))));
    // The variance of the mean the noise would have at 16 spp, rising to the right: its view
    // shows a gradient across two decades.
    Image variance(kWidth, kHeight);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        Rgb ref = batch.reference.at(x, y);
        double relative = noise.stddev() * noise.stddev() / 16 * std::pow(10.0, 2.0 * x / kWidth);
        variance.set(x, y, Rgb{ref.x * ref.x, ref.y * ref.y, ref.z * ref.z} * relative);
      }
    std::string exr = "runs/" + batch.labels[m] + ".r0.exr";
    write_exr((dir / exr).string(), image, &variance, {});
    batch.variances.push_back(std::move(variance));
    json errors = json::array();
    for (const auto& [region, summary] :
         error_summary(image, batch.reference, {{"middle", batch.region}}))
      errors.push_back({{"region", region},
                        {"mrse", summary.mrse},
                        {"mse", summary.mse},
                        {"rmse", summary.rmse}});
    methods.push_back({{"label", batch.labels[m]},
                       {"method", "sa"},
                       {"sampler", "stratified"},
                       {"budget_seconds", nullptr},
                       {"runs",
                        {{{"repeat", 0},
                          {"seed", 1},
                          {"job_id", "local"},
                          {"exr", exr},
                          {"spp", 16},
                          {"compute_seconds", 1.0},
                          {"wall_seconds", 1.0},
                          {"curve", json::array()},
                          {"errors", errors}}}}});
    batch.methods.push_back(std::move(image));
  }
  json result = {
      {"format", "penumbra/batch-result@1"},
      {"batch_id", "local"},
      {"name", "viewer-test"},
      {"scene", {{"name", "synthetic"}, {"hash", "0"}, {"width", kWidth}, {"height", kHeight}}},
      {"regions",
       {{{"name", "middle"},
         {"rect", {batch.region.x0, batch.region.y0, batch.region.x1, batch.region.y1}}}}},
      {"reference",
       {{"exr", "reference.exr"},
        {"method", "bsdf+sa"},
        {"sampler", "stratified"},
        {"spp", 1024},
        {"job_id", "local"},
        {"cached", false}}},
      {"methods", methods}};
  std::ofstream(dir / "batch.json") << result.dump(2);
  return batch;
}

double srgb(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// The display value of a pixel as the page should show it: the embedded (quantized) value
// tonemapped at `exposure`.
std::array<int, 3> tonemapped(const Image& image, int x, int y, double exposure) {
  Image quantized = decode_viewer_image(encode_viewer_image(image), image.width, image.height);
  Rgb value = quantized.at(x, y);
  return {int(std::lround(255 * srgb(value.x * exposure))),
          int(std::lround(255 * srgb(value.y * exposure))),
          int(std::lround(255 * srgb(value.z * exposure)))};
}

void expect_near(const std::array<int, 3>& shown, const std::array<int, 3>& expected, int tolerance,
                 const std::string& what) {
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(shown[size_t(c)], expected[size_t(c)], tolerance)
        << what << ", channel " << c << ": shown " << shown[0] << "," << shown[1] << "," << shown[2]
        << ", expected " << expected[0] << "," << expected[1] << "," << expected[2];
}

TEST(ViewerBrowser, FlipZoomExposureErrorViewsProbeAndLinks) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << "chromium is not installed (" << kChromium << ")";
  const auto start = Clock::now();
  fs::path dir = output_dir();
  SyntheticBatch batch = write_synthetic_batch(dir / "batch");
  write_batch_report(batch.dir, dir / "report");
  const Image quantized_reference =
      decode_viewer_image(encode_viewer_image(batch.reference), kWidth, kHeight);
  const double exposure = choose_exposure(batch.reference);

  Chromium browser(dir);
  browser.set_deadline(start + std::chrono::seconds(20));
  Page page(browser);
  const std::string url = "file://" + fs::absolute(dir / "report" / "report.html").string();
  page.call("Page.navigate", {{"url", url}});
  browser.wait_event("Page.loadEventFired");
  // The images decode asynchronously.
  page.eval(
      "new Promise(function(done){(function check(){var v=document.getElementById('viewer');"
      "if(v.hasAttribute('data-ready')||v.hasAttribute('data-error'))done();"
      "else setTimeout(check,20);})();})");
  ASSERT_EQ(page.attribute("data-error"), "");
  ASSERT_EQ(page.attribute("data-ready"), "1");
  EXPECT_DOUBLE_EQ(page.eval("JSON.parse(document.getElementById('viewer-data').textContent)"
                             ".exposure")
                       .get<double>(),
                   exposure);

  // The first method is shown; key 2 shows the second, Space flips to the reference and back.
  EXPECT_EQ(page.attribute("data-shown"), "low-noise");
  page.key("2", "Digit2", 50);
  EXPECT_EQ(page.attribute("data-shown"), "high-noise");
  page.key(" ", "Space", 32);
  EXPECT_EQ(page.attribute("data-shown"), "reference");
  page.key(" ", "Space", 32);
  EXPECT_EQ(page.attribute("data-shown"), "high-noise");

  // Fitted: the 768-pixel-wide canvas shows the 64-pixel image at 12x, centred on (32, 24); the
  // canvas pixel (384, 288) shows image pixel (32, 24).
  EXPECT_DOUBLE_EQ(std::stod(page.attribute("data-zoom")), 12.0);
  expect_near(page.pixel(384, 288), tonemapped(batch.methods[1], 32, 24, exposure), 1, "fit");
  page.screenshot(dir / "viewer-fit.png");

  // Two zoom steps: 48 screen pixels per image pixel, all the same colour (nearest neighbour),
  // and the crops (176 pixels wide: 11x) show the same image pixel at their centres.
  page.key("+", "Equal", 187);
  page.key("+", "Equal", 187);
  EXPECT_DOUBLE_EQ(std::stod(page.attribute("data-zoom")), 48.0);
  json block = page.eval(
      "(function(){var d=document.querySelector('#viewer .pv-canvas').getContext('2d')"
      ".getImageData(384,288,48,48).data,first=[d[0],d[1],d[2]],same=0;"
      "for(var i=0;i<d.length;i+=4)same+=d[i]===first[0]&&d[i+1]===first[1]&&d[i+2]===first[2];"
      "return same;})()");
  EXPECT_EQ(block.get<int>(), 48 * 48);
  expect_near(page.pixel(384, 288), tonemapped(batch.methods[1], 32, 24, exposure), 1, "zoom 48");
  expect_near(page.pixel(383, 287), tonemapped(batch.methods[1], 31, 23, exposure), 1,
              "zoom 48, the pixel up-left");
  const std::vector<const Image*> crops = {&batch.reference, &batch.methods[0], &batch.methods[1]};
  for (size_t crop = 0; crop < crops.size(); ++crop)
    expect_near(page.pixel(88, 66, int(crop)), tonemapped(*crops[crop], 32, 24, exposure), 1,
                "crop " + std::to_string(crop));
  page.screenshot(dir / "viewer-zoom48.png");

  // Exposure: ] twice is +1 stop; the slider to -2 stops.
  page.key("]", "BracketRight", 221);
  page.key("]", "BracketRight", 221);
  EXPECT_EQ(page.attribute("data-stops"), "1");
  expect_near(page.pixel(384, 288), tonemapped(batch.methods[1], 32, 24, 2 * exposure), 1, "+1");
  page.eval(
      "(function(){var s=document.querySelector('#viewer .pv-exposure input');s.value='-2';"
      "s.dispatchEvent(new Event('input'));})()");
  expect_near(page.pixel(384, 288), tonemapped(batch.methods[1], 32, 24, exposure / 4), 1, "-2");
  // Against the EXR's own value: within the quantization (0.4%), a level or two at 8 bits.
  {
    Rgb value = batch.methods[1].at(32, 24);
    std::array<int, 3> exact;
    for (int c = 0; c < 3; ++c)
      exact[size_t(c)] = int(std::lround(255 * srgb(value[c] * exposure / 4)));
    expect_near(page.pixel(384, 288), exact, 2, "against the EXR");
  }

  // The relative error view: viridis of mean |x - ref| / (ref + 0.01) over the figure's scale.
  page.key("e", "KeyE", 69);
  EXPECT_EQ(page.attribute("data-view"), "error");
  json scale = page.eval("JSON.parse(document.getElementById('viewer-data').textContent)");
  const double error_scale = scale["error_scale"].get<double>();
  const double difference_scale = scale["difference_scale"].get<double>();
  const Image quantized =
      decode_viewer_image(encode_viewer_image(batch.methods[1]), kWidth, kHeight);
  {
    double sum = 0, signed_sum = 0;
    for (int c = 0; c < 3; ++c) {
      double x = quantized.at(32, 24)[c], r = quantized_reference.at(32, 24)[c];
      sum += std::abs(x - r) / (r + 0.01);
      signed_sum += x - r;
    }
    Rgb colour = viridis(sum / 3 / error_scale);
    expect_near(page.pixel(384, 288),
                {int(std::lround(255 * colour.x)), int(std::lround(255 * colour.y)),
                 int(std::lround(255 * colour.z))},
                1, "relative error");
    // The signed difference: white at 0, towards red (178, 24, 43) above, blue below.
    page.key("d", "KeyD", 68);
    EXPECT_EQ(page.attribute("data-view"), "difference");
    double t = std::clamp(signed_sum / 3 / difference_scale, -1.0, 1.0);
    std::array<int, 3> end =
        t < 0 ? std::array<int, 3>{33, 102, 172} : std::array<int, 3>{178, 24, 43};
    std::array<int, 3> expected;
    for (size_t c = 0; c < 3; ++c)
      expected[c] = int(std::lround(247 * (1 - std::abs(t)) + end[c] * std::abs(t)));
    expect_near(page.pixel(384, 288), expected, 1, "signed difference");
  }
  // The variance view: viridis of the relative variance mean(var / (ref^2 + 1e-6)) on the
  // logarithmic scale chosen from every method's variance layer.
  {
    page.key("v", "KeyV", 86);
    EXPECT_EQ(page.attribute("data-view"), "variance");
    const auto [low, high] =
        choose_variance_scale({&batch.variances[0], &batch.variances[1]}, batch.reference);
    EXPECT_DOUBLE_EQ(scale["variance_scale"][0].get<double>(), low);
    EXPECT_DOUBLE_EQ(scale["variance_scale"][1].get<double>(), high);
    EXPECT_LT(low, high);
    const Image quantized_variance =
        decode_viewer_image(encode_viewer_image(batch.variances[1]), kWidth, kHeight);
    // The canvas centre shows image pixel (32, 24); the canvas pixel up-left of it (31, 23).
    for (const auto& [canvas_x, canvas_y, x, y] :
         {std::array<int, 4>{384, 288, 32, 24}, std::array<int, 4>{383, 287, 31, 23}}) {
      double relative = 0;
      for (int c = 0; c < 3; ++c) {
        double r = quantized_reference.at(x, y)[c];
        relative += quantized_variance.at(x, y)[c] / (r * r + kMrseEpsilon);
      }
      relative /= 3;
      Rgb colour =
          viridis((std::log10(relative) - std::log10(low)) / (std::log10(high) - std::log10(low)));
      expect_near(page.pixel(canvas_x, canvas_y),
                  {int(std::lround(255 * colour.x)), int(std::lround(255 * colour.y)),
                   int(std::lround(255 * colour.z))},
                  1, "relative variance at " + std::to_string(x) + ", " + std::to_string(y));
    }
    json legend = page.eval("document.querySelector('#viewer .pv-scale').textContent");
    EXPECT_NE(legend.get<std::string>().find("log scale"), std::string::npos) << legend;
  }
  page.key("i", "KeyI", 73);
  EXPECT_EQ(page.attribute("data-view"), "image");

  // The probe: the mouse over the canvas centre lists pixel (32, 24) and the reference's value.
  json box = page.eval(
      "(function(){var c=document.querySelector('#viewer .pv-canvas');c.scrollIntoView();"
      "var r=c.getBoundingClientRect();return [r.left,r.top];})()");
  page.call("Input.dispatchMouseEvent", {{"type", "mouseMoved"},
                                         {"x", box[0].get<double>() + 1 + 384.5},
                                         {"y", box[1].get<double>() + 1 + 288.5}});
  json probe = page.eval(
      "Array.from(document.querySelectorAll('#viewer .pv-probe tr')).map(function(r){"
      "return Array.from(r.children).map(function(c){return c.textContent;});})");
  ASSERT_GE(probe.size(), 4u) << probe.dump();
  EXPECT_EQ(probe[0][0], "pixel 32, 24");
  EXPECT_EQ(probe[1][0], "reference");
  EXPECT_NEAR(std::stod(probe[1][1].get<std::string>()), batch.reference.at(32, 24).x,
              batch.reference.at(32, 24).x * 2 * kViewerQuantization + 1e-4);

  // A table cell shows its method and region.
  page.eval(
      "document.querySelector('td[data-viewer-label=\"low-noise\"][data-viewer-region=\"middle\"]')"
      ".click()");
  EXPECT_EQ(page.attribute("data-shown"), "low-noise");
  EXPECT_EQ(page.attribute("data-region"), "middle");
  EXPECT_DOUBLE_EQ(std::stod(page.attribute("data-cx")), 20.0);
  EXPECT_DOUBLE_EQ(std::stod(page.attribute("data-cy")), 16.0);

  // No console errors or exceptions, and no request but the page itself.
  int requests = 0;
  for (const json& event : browser.events()) {
    const std::string method = event.value("method", "");
    if (method == "Runtime.exceptionThrown") ADD_FAILURE() << event.dump();
    if (method == "Runtime.consoleAPICalled" && event["params"].value("type", "") == "error")
      ADD_FAILURE() << event.dump();
    if (method == "Network.requestWillBeSent") {
      std::string request = event["params"]["request"].value("url", "");
      if (request.rfind("data:", 0) == 0) continue;
      ++requests;
      EXPECT_EQ(request, url);
    }
  }
  EXPECT_EQ(requests, 1);
  // Without a reference (a farm job that has none), in a second tab of the same browser: the
  // image alone, no flip, split, error or difference view, its variance relative to itself.
  {
    ComparisonViewerContent content;
    content.width = kWidth;
    content.height = kHeight;
    content.regions.push_back({"middle", batch.region});
    ViewerImage job;
    job.label = "a-job";
    job.method = "sa";
    job.sampler = "stratified";
    job.spp = 16;
    job.image = &batch.methods[1];
    job.variance = &batch.variances[1];
    content.methods.push_back(job);
    choose_viewer_scales(content);
    EXPECT_DOUBLE_EQ(content.exposure, choose_exposure(batch.methods[1]));
    std::ofstream(dir / "job.html")
        << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"></head><body>\n"
        << comparison_viewer_html(content) << "</body></html>\n";
    Page job_page(browser);
    const std::string job_url = "file://" + fs::absolute(dir / "job.html").string();
    job_page.call("Page.navigate", {{"url", job_url}});
    job_page.wait_for_viewer(start + std::chrono::seconds(20));
    ASSERT_EQ(job_page.attribute("data-error"), "");
    EXPECT_EQ(job_page.attribute("data-shown"), "a-job");
    EXPECT_EQ(job_page.eval("document.querySelectorAll('#viewer [data-view]').length").get<int>(),
              2);  // image and variance
    job_page.key("e", "KeyE", 69);
    job_page.key(" ", "Space", 32);
    job_page.key("r", "KeyR", 82);
    EXPECT_EQ(job_page.attribute("data-view"), "image");
    EXPECT_EQ(job_page.attribute("data-shown"), "a-job");
    expect_near(job_page.pixel(384, 288), tonemapped(batch.methods[1], 32, 24, content.exposure), 1,
                "no reference, image");
    job_page.key("v", "KeyV", 86);
    EXPECT_EQ(job_page.attribute("data-view"), "variance");
    const Image image = decode_viewer_image(encode_viewer_image(batch.methods[1]), kWidth, kHeight);
    const Image variance =
        decode_viewer_image(encode_viewer_image(batch.variances[1]), kWidth, kHeight);
    double relative = 0;
    for (int c = 0; c < 3; ++c) {
      double x = image.at(32, 24)[c];
      relative += variance.at(32, 24)[c] / (x * x + kMrseEpsilon);
    }
    relative /= 3;
    const double low = content.variance_low, high = content.variance_high;
    EXPECT_LT(low, high);
    Rgb colour =
        viridis((std::log10(relative) - std::log10(low)) / (std::log10(high) - std::log10(low)));
    expect_near(job_page.pixel(384, 288),
                {int(std::lround(255 * colour.x)), int(std::lround(255 * colour.y)),
                 int(std::lround(255 * colour.z))},
                1, "no reference, variance relative to the image");
    for (const json& event : browser.events()) {
      if (event.value("sessionId", "") != job_page.session()) continue;
      const std::string method = event.value("method", "");
      if (method == "Runtime.exceptionThrown") ADD_FAILURE() << event.dump();
      if (method == "Runtime.consoleAPICalled" && event["params"].value("type", "") == "error")
        ADD_FAILURE() << event.dump();
    }
  }

  // Attached to the test's output: GoogleTest's XML report (--gtest_output=xml) lists them as
  // properties, ctest's as ATTACHED_FILES (tests/CMakeLists.txt), and the log names them.
  RecordProperty("screenshot_fit", (dir / "viewer-fit.png").string());
  RecordProperty("screenshot_zoom48", (dir / "viewer-zoom48.png").string());
  std::printf("viewer screenshots: %s, %s (%.1f s)\n", (dir / "viewer-fit.png").c_str(),
              (dir / "viewer-zoom48.png").c_str(),
              std::chrono::duration<double>(Clock::now() - start).count());
}

}  // namespace
}  // namespace penumbra
