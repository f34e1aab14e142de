// One HTTP GET through libcurl (see http_fetch.hpp).
#include "deflex/sensors/detail/http_fetch.hpp"

#include <curl/curl.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>

#include "deflex/text/errors.hpp"

namespace deflex {
namespace {

struct Body {
  std::string text;
  std::size_t max_bytes = 0;
  bool too_large = false;
};

extern "C" std::size_t append_body(char* data, std::size_t size, std::size_t count, void* user) {
  auto* body = static_cast<Body*>(user);
  const std::size_t n = size * count;
  if (body->text.size() + n > body->max_bytes) {
    body->too_large = true;
    return 0;  // makes curl stop with CURLE_WRITE_ERROR
  }
  body->text.append(data, n);
  return n;
}

struct CurlDeleter {
  void operator()(CURL* c) const { curl_easy_cleanup(c); }
};

}  // namespace

std::string http_get_text(const std::string& url, double timeout_s, std::size_t max_bytes) {
  // curl_global_init is not thread-safe; once per process, before the first handle.
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
  if (!(timeout_s > 0.0) || !std::isfinite(timeout_s)) {
    throw InputError(fmt::format("{}: the HTTP timeout must be a positive number of seconds", url));
  }
  std::unique_ptr<CURL, CurlDeleter> curl(curl_easy_init());
  if (!curl) {
    throw Error(fmt::format("{}: could not start an HTTP request (libcurl)", url));
  }
  Body body;
  body.max_bytes = max_bytes;
  char error[CURL_ERROR_SIZE] = {};
  const long timeout_ms = std::max(1L, static_cast<long>(std::lround(timeout_s * 1000.0)));
  curl_easy_setopt(curl.get(), CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl.get(), CURLOPT_ERRORBUFFER, error);
  curl_easy_setopt(curl.get(), CURLOPT_TIMEOUT_MS, timeout_ms);
  curl_easy_setopt(curl.get(), CURLOPT_CONNECTTIMEOUT_MS, timeout_ms);
  curl_easy_setopt(curl.get(), CURLOPT_NOSIGNAL, 1L);  // no SIGALRM for the timeout: safe beside other threads
  // A sensor sits on the cell's own network: a proxy from the environment (http_proxy) would send the
  // request where the sensor is not.
  curl_easy_setopt(curl.get(), CURLOPT_NOPROXY, "*");
  curl_easy_setopt(curl.get(), CURLOPT_FOLLOWLOCATION, 1L);
  curl_easy_setopt(curl.get(), CURLOPT_MAXREDIRS, 3L);
  // A sensor's configuration is plain HTTP on the cell's network; nothing else is asked for.
  curl_easy_setopt(curl.get(), CURLOPT_PROTOCOLS_STR, "http,https");
  curl_easy_setopt(curl.get(), CURLOPT_WRITEFUNCTION, append_body);
  curl_easy_setopt(curl.get(), CURLOPT_WRITEDATA, &body);
  const CURLcode rc = curl_easy_perform(curl.get());
  if (body.too_large) {
    throw Error(
        fmt::format("{}: the reply is larger than {} bytes (not a sensor's configuration page?)", url, max_bytes));
  }
  if (rc != CURLE_OK) {
    throw Error(fmt::format("{}: {} ({})", url, error[0] != '\0' ? error : curl_easy_strerror(rc),
                            rc == CURLE_OPERATION_TIMEDOUT ? fmt::format("no answer within {} s", timeout_s)
                                                           : "is the address right and the sensor on this network?"));
  }
  long status = 0;
  curl_easy_getinfo(curl.get(), CURLINFO_RESPONSE_CODE, &status);
  if (status != 200) {
    throw Error(fmt::format("{}: HTTP status {} (expected 200)", url, status));
  }
  return body.text;
}

}  // namespace deflex
