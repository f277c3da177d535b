#pragma once
// LCM channel names; rates and senders are in docs/protocol.md.
namespace pcisim::protocol {

inline constexpr const char* kInstrumentChannel = "PCISIM_INSTRUMENT";  // bridge -> server, 1 kHz
inline constexpr const char* kForceChannel = "PCISIM_FORCE";            // server -> bridge, 1 kHz
inline constexpr const char* kWireChannel = "PCISIM_WIRE";              // server, physics rate
inline constexpr const char* kStatusChannel = "PCISIM_STATUS";          // server, 1 Hz
inline constexpr const char* kMetricsChannel = "PCISIM_METRICS";        // server, 1 Hz: the debrief so far
inline constexpr const char* kSessionChannel = "PCISIM_SESSION";        // consoles -> server
inline constexpr const char* kXrayChannel = "PCISIM_XRAY";              // server, pulse rate, own instance
inline constexpr const char* kProbeChannel = "PCISIM_PROBE";            // bridge -> server, 1 kHz
inline constexpr const char* kUltrasoundChannel = "PCISIM_ULTRASOUND";  // server, frame rate, image instance

}  // namespace pcisim::protocol
