// Reading one small text document over HTTP (a sensor's configuration page, such as an ATI Net F/T's
// netftapi2.xml). Set-up time only: it blocks, allocates and throws. Built on libcurl (Debian's
// libcurl4-openssl-dev), not on a request written by hand: redirects, chunked replies and timeouts
// are its business, and it is maintained. Proxies are bypassed: a sensor is on the cell's network.
#pragma once

#include <cstddef>
#include <string>

namespace deflex {

/// GETs `url` ("http://192.168.1.1/netftapi2.xml") and returns the body. Waits at most `timeout_s`
/// for the whole transfer; refuses a body larger than `max_bytes`. Throws Error naming the URL and
/// the reason (unreachable, timed out, HTTP status other than 200, too large).
[[nodiscard]] std::string http_get_text(const std::string& url, double timeout_s, std::size_t max_bytes = 1u << 20);

}  // namespace deflex
