#pragma once
// The Host header against DNS rebinding: a web page on another origin whose name the
// attacker points at 127.0.0.1 makes the browser send that name as Host. Only names this
// host answers to are accepted: IP literals, "localhost", this machine's hostname, and
// the names an operator configures (http.allowed_hosts).
#include <string>
#include <string_view>
#include <vector>

namespace robodiff::server {

// The host part of a Host header value, without the port, lower-cased ("[::1]:80" ->
// "::1"); empty when malformed.
std::string hostOfHeader(std::string_view header);

// True when `header` (a Host value) names an IP literal, localhost (or a subdomain of
// it, which resolvers keep on loopback), or one of `names` (compared case-insensitively).
bool hostAllowed(std::string_view header, const std::vector<std::string>& names);

}  // namespace robodiff::server
