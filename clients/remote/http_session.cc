#include "clients/remote/http_session.h"

#include <fstream>

#include <algorithm>
#include <cmath>
#include <boost/beast/websocket.hpp>
#include <spdlog/spdlog.h>

#include "clients/remote/access_tokens.h"
#include "clients/remote/hub.h"
#include "clients/remote/request_target.h"
#include "clients/remote/web_assets.h"
#include "clients/remote/ws_session.h"

namespace pcisim::remote {

namespace beast = boost::beast;
namespace http = beast::http;

HttpSession::HttpSession(boost::asio::ip::tcp::socket&& socket, Hub& hub, const AccessTokens& tokens,
                         const std::string& debrief_html)
    : stream_(std::move(socket)), hub_(hub), tokens_(tokens), debrief_html_(debrief_html) {}

void HttpSession::run() {
  read();
}

void HttpSession::read() {
  parser_.emplace();
  parser_->header_limit(8192);
  parser_->body_limit(4096);
  stream_.expires_after(std::chrono::seconds(30));
  http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
}

namespace {
std::string_view sv(beast::string_view s) {
  return {s.data(), s.size()};
}

http::response<http::string_body> plain(unsigned version, http::status status, std::string text) {
  http::response<http::string_body> res{status, version};
  res.set(http::field::server, "pcisim-remote");
  res.set(http::field::content_type, "text/plain; charset=utf-8");
  res.set(http::field::cache_control, "no-store");
  res.body() = std::move(text);
  res.prepare_payload();
  return res;
}
}  // namespace

void HttpSession::on_read(beast::error_code ec, size_t) {
  if (ec) return;  // end of stream, timeout or a malformed request: drop the connection
  auto req = parser_->release();
  if (beast::websocket::is_upgrade(req)) return upgrade(std::move(req));
  const unsigned version = req.version();
  const bool keep_alive = req.keep_alive();
  if (req.method() != http::verb::get && req.method() != http::verb::head) {
    auto res = plain(version, http::status::method_not_allowed, "GET only\n");
    res.keep_alive(keep_alive);
    return respond(std::move(res));
  }
  if (target_path(sv(req.target())) == "/debrief.html") return debrief(req);
  const WebAsset* asset = find_web_asset(target_path(sv(req.target())));
  if (!asset) {
    auto res = plain(version, http::status::not_found, "not found\n");
    res.keep_alive(keep_alive);
    return respond(std::move(res));
  }
  http::response<http::string_body> res{http::status::ok, version};
  res.set(http::field::server, "pcisim-remote");
  res.set(http::field::content_type, beast::string_view(asset->content_type.data(), asset->content_type.size()));
  res.set(http::field::cache_control, "no-store");
  // everything the page needs comes from here: no CDN, no inline script, no framing by others
  res.set("Content-Security-Policy",
          "default-src 'self'; img-src 'self' blob: data:; connect-src 'self' ws: wss:; frame-ancestors 'none'");
  res.set("X-Content-Type-Options", "nosniff");
  res.set("Referrer-Policy", "no-referrer");
  if (req.method() == http::verb::get) res.body() = std::string(asset->body);
  res.prepare_payload();
  if (req.method() == http::verb::head) res.content_length(asset->body.size());
  res.keep_alive(keep_alive);
  respond(std::move(res));
}

// the server's debrief page, to a page that holds a token (it is the session's record): read from
// the file the server writes at the end of a session or when asked (CMD_DEBRIEF)
void HttpSession::debrief(const http::request<http::string_body>& req) {
  const unsigned version = req.version();
  const bool keep_alive = req.keep_alive();
  const auto done = [&](http::response<http::string_body> res) {
    res.keep_alive(keep_alive);
    respond(std::move(res));
  };
  std::string token = query_param(sv(req.target()), "token").value_or("");
  if (token.empty()) token = bearer_token(sv(req[http::field::authorization]));
  if (token.empty()) return done(plain(version, http::status::unauthorized, "token required\n"));
  if (!tokens_.role_of(token)) return done(plain(version, http::status::forbidden, "wrong token\n"));
  if (debrief_html_.empty())
    return done(plain(version, http::status::not_found, "this gateway serves no debrief (--debrief-html)\n"));
  std::ifstream in(debrief_html_, std::ios::binary);
  std::string body;
  if (in) {
    // (a page is under a megabyte or so; a file past 16 MB is not the server's)
    in.seekg(0, std::ios::end);
    const auto size = static_cast<std::streamoff>(in.tellg());
    if (size > (16 << 20))
      return done(plain(version, http::status::internal_server_error,
                        "the debrief file is over 16 MB: not the server's page\n"));
    if (size > 0) {
      body.resize(static_cast<size_t>(size));
      in.seekg(0);
      in.read(body.data(), size);
      if (!in) body.clear();
    }
  }
  if (body.empty())
    return done(plain(version, http::status::not_found,
                      "no debrief yet: the server writes it at the end of the session, or when asked\n"));
  http::response<http::string_body> res{http::status::ok, version};
  res.set(http::field::server, "pcisim-remote");
  res.set(http::field::content_type, "text/html; charset=utf-8");
  res.set(http::field::cache_control, "no-store");
  // the page is self-contained: its own style and embedded images, no script, nothing fetched
  res.set("Content-Security-Policy",
          "default-src 'none'; img-src data:; style-src 'unsafe-inline'; frame-ancestors 'none'; sandbox");
  res.set("X-Content-Type-Options", "nosniff");
  res.set("Referrer-Policy", "no-referrer");
  const size_t bytes = body.size();
  if (req.method() == http::verb::get) res.body() = std::move(body);
  res.prepare_payload();
  if (req.method() == http::verb::head) res.content_length(bytes);
  done(std::move(res));
}

void HttpSession::upgrade(http::request<http::string_body>&& req) {
  const unsigned version = req.version();
  if (target_path(sv(req.target())) != "/ws") return respond(plain(version, http::status::not_found, "not found\n"));
  std::string token = query_param(sv(req.target()), "token").value_or("");
  if (token.empty()) token = bearer_token(sv(req[http::field::authorization]));
  if (token.empty()) {
    spdlog::warn("remote: refused a connection without a token");
    return respond(plain(version, http::status::unauthorized, "token required\n"));
  }
  const auto role = tokens_.role_of(token);
  if (!role) {
    spdlog::warn("remote: refused a connection with a wrong token");
    return respond(plain(version, http::status::forbidden, "wrong token\n"));
  }
  if (hub_.full(*role)) return respond(plain(version, http::status::service_unavailable, "too many connections\n"));
  // a page may ask for fewer frames; anything unreadable or non-finite ("nan", "inf") gets the cap
  double fps = hub_.limits().max_fps;
  if (const auto asked = query_param(sv(req.target()), "fps")) {
    try {
      const double want = std::stod(*asked);
      if (std::isfinite(want)) fps = std::clamp(want, 0.5, hub_.limits().max_fps);
    } catch (const std::exception&) {}
  }
  stream_.expires_never();  // the WebSocket keeps its own timeouts
  std::make_shared<WsSession>(stream_.release_socket(), hub_, *role, fps)->start(std::move(req));
}

void HttpSession::respond(http::response<http::string_body>&& res) {
  response_ = std::make_shared<http::response<http::string_body>>(std::move(res));
  const bool close = !response_->keep_alive() || response_->result() == http::status::unauthorized ||
                     response_->result() == http::status::forbidden;
  if (close) response_->keep_alive(false);
  http::async_write(stream_, *response_, [self = shared_from_this(), close](beast::error_code ec, size_t) {
    if (ec || close) {
      beast::error_code ignored;
      self->stream_.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_send, ignored);
      return;
    }
    self->read();
  });
}

}  // namespace pcisim::remote
