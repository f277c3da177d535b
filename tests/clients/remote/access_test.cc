// Who may connect: the page loads for anyone, the WebSocket only with a token, and the token's
// role decides what the connection may do. Real sockets on loopback.
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <set>

#include "clients/remote/request_target.h"
#include "remote_test_support.h"

namespace pcisim::remote::test {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;

http::response<http::string_body> http_get(uint16_t port, const std::string& target) {
  net::io_context io;
  beast::tcp_stream stream(io);
  stream.connect({net::ip::address_v4::loopback(), port});
  http::request<http::empty_body> req{http::verb::get, target, 11};
  req.set(http::field::host, "127.0.0.1");
  http::write(stream, req);
  beast::flat_buffer buf;
  http::response<http::string_body> res;
  http::read(stream, buf, res);
  return res;
}

TEST(RemoteAccess, TokensAreRandomHexAndDistinct) {
  std::set<std::string> seen;
  for (int i = 0; i < 100; ++i) {
    const std::string t = AccessTokens::random_token();
    EXPECT_EQ(t.size(), 32u);
    EXPECT_EQ(t.find_first_not_of("0123456789abcdef"), std::string::npos) << t;
    seen.insert(t);
  }
  EXPECT_EQ(seen.size(), 100u);
  const AccessTokens tokens;
  EXPECT_NE(tokens.observer(), tokens.controller());
  EXPECT_EQ(tokens.role_of(tokens.observer()), Role::kObserver);
  EXPECT_EQ(tokens.role_of(tokens.controller()), Role::kController);
  EXPECT_FALSE(tokens.role_of(""));
  EXPECT_FALSE(tokens.role_of(tokens.controller().substr(0, 31)));
  EXPECT_FALSE(tokens.role_of(tokens.controller() + "0"));
  EXPECT_THROW(AccessTokens("same", "same"), std::invalid_argument);
}

TEST(RemoteAccess, PageLoadsWithoutTokenAndSaysTokenRequired) {
  TestGateway g;
  const auto page = http_get(g.port(), "/");
  EXPECT_EQ(page.result(), http::status::ok);
  EXPECT_NE(page[http::field::content_type].find("text/html"), beast::string_view::npos);
  EXPECT_NE(page.body().find("token required"), std::string::npos);
  EXPECT_NE(page.body().find("/app.js"), std::string::npos);
  // everything comes from the gateway: no script or style from anywhere else
  EXPECT_EQ(page.body().find("http://"), std::string::npos);
  EXPECT_EQ(page.body().find("https://"), std::string::npos);
  const auto js = http_get(g.port(), "/app.js");
  EXPECT_EQ(js.result(), http::status::ok);
  EXPECT_NE(js.body().find("WebSocket"), std::string::npos);
  EXPECT_EQ(http_get(g.port(), "/style.css").result(), http::status::ok);
  EXPECT_EQ(http_get(g.port(), "/secret").result(), http::status::not_found);
  EXPECT_EQ(http_get(g.port(), "/../../etc/passwd").result(), http::status::not_found);
}

TEST(RemoteAccess, WebSocketWithoutTokenIs401AndWithWrongTokenIs403) {
  TestGateway g;
  WsClient none, empty, wrong, guessed;
  EXPECT_EQ(none.connect(g.port(), "/ws"), 401);
  EXPECT_EQ(empty.connect(g.port(), "/ws?token="), 401);
  EXPECT_EQ(wrong.connect(g.port(), "/ws?token=nottherighttoken"), 403);
  // a token for another path does not open the socket either
  EXPECT_EQ(guessed.connect(g.port(), std::string("/other?token=") + kControllerToken), 404);
  EXPECT_EQ(g.gateway->hub_stats().clients, 0);
}

TEST(RemoteAccess, ObserverAndControllerTokensGiveTheirRoles) {
  TestGateway g;
  WsClient observer, controller, bearer;
  ASSERT_EQ(observer.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_EQ(controller.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_EQ(bearer.connect(g.port(), "/ws", true, 0, std::string("Bearer ") + kObserverToken), 101);
  const auto h1 = observer.next_of("hello");
  const auto h2 = controller.next_of("hello");
  const auto h3 = bearer.next_of("hello");
  ASSERT_TRUE(h1 && h2 && h3);
  EXPECT_EQ((*h1)["role"], "observer");
  EXPECT_EQ((*h2)["role"], "controller");
  EXPECT_EQ((*h3)["role"], "observer");
  EXPECT_NE((*h1)["id"], (*h2)["id"]);
  EXPECT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 3; }));
}

// observers fill all but one slot: the controller always gets in (64 observers once locked it out)
TEST(RemoteAccess, ConnectionsBeyondTheLimitAreRefusedButTheControllerAlwaysGetsIn) {
  GatewayOptions o;
  o.hub.max_clients = 3;
  TestGateway g(o);
  WsClient a, b, c, controller, d;
  ASSERT_EQ(a.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_EQ(b.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 2; }));
  EXPECT_EQ(c.connect(g.port(), ws_target(kObserverToken)), 503) << "the last slot is the controller's";
  EXPECT_EQ(controller.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 3; }));
  EXPECT_EQ(d.connect(g.port(), ws_target(kControllerToken)), 503) << "then nobody";
}

// the auth scheme is case-insensitive (RFC 7235); a lower-case "bearer" was refused
TEST(RemoteAccess, TheBearerSchemeIsCaseInsensitive) {
  EXPECT_EQ(bearer_token("Bearer abc"), "abc");
  EXPECT_EQ(bearer_token("bearer abc"), "abc");
  EXPECT_EQ(bearer_token("BEARER  abc"), "abc");
  EXPECT_EQ(bearer_token("Bearerabc"), "");
  EXPECT_EQ(bearer_token("Basic abc"), "");
  EXPECT_EQ(bearer_token("bear"), "");
  TestGateway g;
  WsClient lower;
  EXPECT_EQ(lower.connect(g.port(), "/ws", true, 0, std::string("bearer ") + kObserverToken), 101);
}

// issue #35: the server's debrief page, served to a page holding a token from the file the server
// writes (read when asked: a debrief written later is the one served)
TEST(RemoteAccess, TheDebriefPageNeedsATokenAndIsReadFromTheServersFile) {
  const std::string path = ::testing::TempDir() + "pcisim-debrief-" + std::to_string(::getpid()) + ".html";
  std::remove(path.c_str());
  GatewayOptions o;
  o.debrief_html = path;
  TestGateway g(o);
  EXPECT_EQ(http_get(g.port(), "/debrief.html").result(), http::status::unauthorized);
  EXPECT_EQ(http_get(g.port(), "/debrief.html?token=nope").result(), http::status::forbidden);
  const std::string with_token = std::string("/debrief.html?token=") + kObserverToken;
  const auto none = http_get(g.port(), with_token);
  EXPECT_EQ(none.result(), http::status::not_found);
  EXPECT_NE(none.body().find("no debrief yet"), std::string::npos);
  std::ofstream(path) << "<!DOCTYPE html><html><body>the debrief</body></html>\n";
  const auto page = http_get(g.port(), with_token);
  ASSERT_EQ(page.result(), http::status::ok);
  EXPECT_EQ(page.body(), "<!DOCTYPE html><html><body>the debrief</body></html>\n");
  EXPECT_EQ(page[http::field::content_type], "text/html; charset=utf-8");
  EXPECT_NE(std::string(page["Content-Security-Policy"]).find("default-src 'none'"), std::string::npos)
      << "nothing the page could fetch or run";
  std::remove(path.c_str());
  // a gateway told of no page says so
  TestGateway plain;
  const auto no_page = http_get(plain.port(), with_token);
  EXPECT_EQ(no_page.result(), http::status::not_found);
  EXPECT_NE(no_page.body().find("serves no debrief"), std::string::npos);
}

}  // namespace
}  // namespace pcisim::remote::test
