#pragma once
// One HTTP connection: serves the embedded page to anyone, and hands a WebSocket upgrade on /ws
// to a WsSession only with a valid token (401 without one, 403 with a wrong one). With a token it
// also serves the server's debrief page (/debrief.html: the file the server writes, read when asked).
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <memory>
#include <optional>
#include <string>

namespace pcisim::remote {

class Hub;
class AccessTokens;

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  // `debrief_html`: the server's debrief page on this host ("": none served)
  HttpSession(boost::asio::ip::tcp::socket&& socket, Hub& hub, const AccessTokens& tokens,
              const std::string& debrief_html = "");
  void run();

 private:
  void read();
  void on_read(boost::beast::error_code ec, size_t bytes);
  void upgrade(boost::beast::http::request<boost::beast::http::string_body>&& req);
  void debrief(const boost::beast::http::request<boost::beast::http::string_body>& req);
  void respond(boost::beast::http::response<boost::beast::http::string_body>&& res);

  boost::beast::tcp_stream stream_;
  boost::beast::flat_buffer buffer_;
  std::optional<boost::beast::http::request_parser<boost::beast::http::string_body>> parser_;
  std::shared_ptr<boost::beast::http::response<boost::beast::http::string_body>> response_;
  Hub& hub_;
  const AccessTokens& tokens_;
  const std::string debrief_html_;
};

}  // namespace pcisim::remote
