// What a page may ask of the server: observers nothing; controllers the session commands, each
// range-checked and rate-limited per connection, delivered to the LCM session channel.
#include <gtest/gtest.h>

#include "clients/remote/session_command_parser.h"
#include "clients/remote/token_bucket.h"
#include "remote_test_support.h"

namespace pcisim::remote::test {
namespace {

using C = pcisim_lcm::session_command_t;
using nlohmann::json;

const C* ok(const ParsedCommand& p) {
  return std::get_if<C>(&p);
}
std::string code(const ParsedCommand& p) {
  const auto* e = std::get_if<CommandError>(&p);
  return e ? e->code : "";
}

TEST(RemoteCommands, ParserKnowsThePermittedCommandsAndTheirRanges) {
  const CommandLimits lim;
  auto p = parse_session_command(json{{"command", "carm"}, {"primary_deg", -45.5}, {"secondary_deg", 20}}, lim);
  ASSERT_TRUE(ok(p));
  EXPECT_EQ(ok(p)->command, C::CMD_CARM);
  EXPECT_DOUBLE_EQ(ok(p)->primary_angle_deg, -45.5);
  EXPECT_DOUBLE_EQ(ok(p)->secondary_angle_deg, 20);
  // the server's limits: |primary| <= 180, |secondary| <= 90
  EXPECT_TRUE(ok(parse_session_command(json{{"command", "carm"}, {"primary_deg", 180}, {"secondary_deg", -90}}, lim)));
  EXPECT_EQ(code(parse_session_command(json{{"command", "carm"}, {"primary_deg", 181}, {"secondary_deg", 0}}, lim)),
            "out_of_range");
  EXPECT_EQ(code(parse_session_command(json{{"command", "carm"}, {"primary_deg", 0}, {"secondary_deg", -90.5}}, lim)),
            "out_of_range");
  EXPECT_EQ(code(parse_session_command(json{{"command", "carm"}, {"primary_deg", "10"}, {"secondary_deg", 0}}, lim)),
            "bad_command");
  EXPECT_EQ(code(parse_session_command(json{{"command", "carm"}, {"primary_deg", 10}}, lim)), "bad_command");
  EXPECT_EQ(code(parse_session_command(json{{"command", "carm"}, {"primary_deg", true}, {"secondary_deg", 0}}, lim)),
            "bad_command");

  p = parse_session_command(json{{"command", "fluoro"}, {"down", true}}, lim);
  ASSERT_TRUE(ok(p));
  EXPECT_EQ(ok(p)->command, C::CMD_FLUORO_PEDAL);
  EXPECT_EQ(ok(p)->pedal_down, 1);
  p = parse_session_command(json{{"command", "cine"}, {"down", false}}, lim);
  ASSERT_TRUE(ok(p));
  EXPECT_EQ(ok(p)->command, C::CMD_CINE);
  EXPECT_EQ(ok(p)->pedal_down, 0);
  EXPECT_EQ(code(parse_session_command(json{{"command", "fluoro"}, {"down", 1}}, lim)), "bad_command");

  p = parse_session_command(json{{"command", "contrast"}}, lim);
  ASSERT_TRUE(ok(p));
  EXPECT_EQ(ok(p)->command, C::CMD_CONTRAST);
  EXPECT_DOUBLE_EQ(ok(p)->contrast_ml, lim.default_contrast_ml);
  EXPECT_EQ(code(parse_session_command(json{{"command", "contrast"}, {"ml", 100}}, lim)), "out_of_range");
  EXPECT_EQ(code(parse_session_command(json{{"command", "contrast"}, {"ml", 5}, {"ml_s", 0}}, lim)), "out_of_range");

  for (const char* name : {"reset", "pause", "resume"})
    EXPECT_TRUE(ok(parse_session_command(json{{"command", name}}, lim))) << name;
  // the debrief so far, written where the server writes it (issue #35)
  p = parse_session_command(json{{"command", "debrief"}}, lim);
  ASSERT_TRUE(ok(p));
  EXPECT_EQ(ok(p)->command, C::CMD_DEBRIEF);
  // loading a scene names a file on the server's host: not for remote pages
  EXPECT_EQ(code(parse_session_command(json{{"command", "load_scene"}, {"scene_path", "/etc/passwd"}}, lim)),
            "bad_command");
  EXPECT_EQ(code(parse_session_command(json{{"command", 7}}, lim)), "bad_command");
  EXPECT_EQ(code(parse_session_command(json::array(), lim)), "bad_command");
}

TEST(RemoteCommands, TokenBucketAllowsABurstThenTheRate) {
  TokenBucket b(5, 10);
  int64_t t = 1'000'000'000;
  int taken = 0;
  for (int i = 0; i < 20; ++i) taken += b.try_take(t);
  EXPECT_EQ(taken, 10);
  EXPECT_FALSE(b.try_take(t + 100'000'000));  // 0.1 s refills half a token
  EXPECT_TRUE(b.try_take(t + 200'000'000));   // 0.2 s: one
  EXPECT_FALSE(b.try_take(t + 200'000'000));
  taken = 0;
  for (int i = 0; i < 30; ++i) taken += b.try_take(t + 100'000'000'000LL);  // long idle: full again, not more
  EXPECT_EQ(taken, 10);
  TokenBucket c(5, 10);
  EXPECT_TRUE(c.try_take(t));
  EXPECT_TRUE(c.try_take(t - 5'000'000'000LL)) << "a clock going backwards neither refills nor breaks it";
}

TEST(RemoteCommands, ControllerCommandsReachTheSessionChannel) {
  TestGateway g;
  WsClient ctl;
  ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(ctl.next_of("hello"));
  ctl.send({{"type", "command"}, {"id", 1}, {"command", "carm"}, {"primary_deg", 42}, {"secondary_deg", -17}});
  auto ack = ctl.next_of("ack");
  ASSERT_TRUE(ack);
  EXPECT_EQ((*ack)["id"], 1);
  ctl.send({{"type", "command"}, {"id", 2}, {"command", "fluoro"}, {"down", true}});
  ASSERT_TRUE(ctl.next_of("ack"));
  ASSERT_TRUE(eventually([&] { return g.recorder.all().size() == 2; }));
  const auto cmds = g.recorder.all();
  EXPECT_EQ(cmds[0].command, C::CMD_CARM);
  EXPECT_DOUBLE_EQ(cmds[0].primary_angle_deg, 42);
  EXPECT_DOUBLE_EQ(cmds[0].secondary_angle_deg, -17);
  EXPECT_GT(cmds[0].utime, 0);
  EXPECT_EQ(cmds[1].command, C::CMD_FLUORO_PEDAL);
  EXPECT_EQ(cmds[1].pedal_down, 1);
  // the gateway hears the bus too: its state follows
  auto state_shows_pedal = [&] {
    auto s = ctl.next_of("state", 500ms);
    return s && (*s)["fluoro"]["pedal_console"] == true && (*s)["carm"]["primary_deg"] == 42.0;
  };
  EXPECT_TRUE(eventually(state_shows_pedal));
}

TEST(RemoteCommands, BadCommandsAreRefusedAndNothingIsPublished) {
  TestGateway g;
  WsClient ctl;
  ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(ctl.next_of("hello"));
  ctl.send({{"type", "command"}, {"id", 5}, {"command", "carm"}, {"primary_deg", 200}, {"secondary_deg", 0}});
  auto err = ctl.next_of("error");
  ASSERT_TRUE(err);
  EXPECT_EQ((*err)["code"], "out_of_range");
  EXPECT_EQ((*err)["id"], 5);
  ctl.send({{"type", "command"}, {"id", 6}, {"command", "load_scene"}, {"scene_path", "x.json"}});
  err = ctl.next_of("error");
  ASSERT_TRUE(err);
  EXPECT_EQ((*err)["code"], "bad_command");
  ctl.send({{"type", "no_such_thing"}});
  err = ctl.next_of("error");
  ASSERT_TRUE(err);
  EXPECT_EQ((*err)["code"], "bad_message");
  std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(g.recorder.all().empty());
  EXPECT_EQ(g.gateway->hub_stats().commands_forwarded, 0);
}

TEST(RemoteCommands, ObserversMayNotCommand) {
  TestGateway g;
  WsClient obs;
  ASSERT_EQ(obs.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_TRUE(obs.next_of("hello"));
  for (const json& msg : {json{{"type", "command"}, {"command", "pause"}},
                          json{{"type", "command"}, {"command", "fluoro"}, {"down", true}},
                          json{{"type", "keyboard"}, {"enable", true}}, json{{"type", "keys"}, {"insert", 1}}}) {
    obs.send(msg);
    auto err = obs.next_of("error");
    ASSERT_TRUE(err) << msg;
    EXPECT_EQ((*err)["code"], "forbidden") << msg;
  }
  std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(g.recorder.all().empty());
  EXPECT_EQ(g.gateway->hub_stats().commands_refused, 4);
  EXPECT_EQ(g.gateway->keyboard()->owner(), 0u);
}

TEST(RemoteCommands, CommandsAreRateLimitedPerConnection) {
  GatewayOptions o;
  o.hub.command_rate = 2;
  o.hub.command_burst = 5;
  TestGateway g(o);
  WsClient flood, calm;
  ASSERT_EQ(flood.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_EQ(calm.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(flood.next_of("hello") && calm.next_of("hello"));
  for (int i = 0; i < 30; ++i) flood.send({{"type", "command"}, {"id", i}, {"command", "pause"}});
  int acks = 0, limited = 0;
  while (acks + limited < 30) {
    auto m = flood.next(2000ms);
    ASSERT_TRUE(m) << acks << " acks, " << limited << " limited";
    if (m->binary) continue;
    const auto j = m->json();
    if (j["type"] == "ack") ++acks;
    if (j["type"] == "error" && j["code"] == "rate_limited") ++limited;
  }
  // a burst of 5, and at most a token or two refilled while the 30 arrived
  EXPECT_GE(acks, 5);
  EXPECT_LE(acks, 7);
  EXPECT_EQ(acks + limited, 30);
  // the other connection has its own bucket
  calm.send({{"type", "command"}, {"id", 100}, {"command", "resume"}});
  auto ack = calm.next_of("ack");
  ASSERT_TRUE(ack);
  EXPECT_EQ((*ack)["id"], 100);
  ASSERT_TRUE(eventually([&] { return static_cast<int>(g.recorder.all().size()) == acks + 1; }));
  EXPECT_EQ(g.gateway->hub_stats().rate_limited, limited);
  // and the flood's bucket refills at the rate
  std::this_thread::sleep_for(600ms);
  flood.send({{"type", "command"}, {"id", 99}, {"command", "resume"}});
  ack = flood.next_of("ack");
  ASSERT_TRUE(ack);
  EXPECT_EQ((*ack)["id"], 99);
}

TEST(RemoteCommands, OversizedMessagesCloseTheConnection) {
  TestGateway g;
  WsClient ctl;
  ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(ctl.next_of("hello"));
  ctl.send({{"type", "command"}, {"command", "pause"}, {"padding", std::string(10000, 'x')}});
  EXPECT_TRUE(eventually([&] { return ctl.closed(); }));
  EXPECT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 0; }));
  EXPECT_TRUE(g.recorder.all().empty());
}

}  // namespace
}  // namespace pcisim::remote::test
