// libFuzzer target for checkpoints. The input is read as a checkpoint of a
// small fixed state (4 faces, 1 channel, key "0123456789abcdef"); and its
// bytes also fill a state and pass log that are written and read back,
// which must give them back exactly (the reader reaches past the checksum
// only with files the writer made).
#include <cmath>
#include <cstring>

#include "checkpoint.h"
#include "error.h"
#include "fuzz_common.h"

using namespace mpath;

namespace {
const std::string kKey = "0123456789abcdef";

RadiosityState empty_state() {
  RadiosityState state;
  state.channels = 1;
  state.faces = 4;
  for (auto* v : {&state.phi, &state.unshot}) v->assign(4, 0.0);
  return state;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  RadiosityState state = empty_state();
  IterationLog log;
  try {
    read_checkpoint(fuzz::write_input("checkpoint.bin", data, size), kKey, state, log);
  } catch (const InputError&) {
  }

  // Round trip of a state made of the input's bytes (finite values only:
  // a checkpoint with a non-finite radiosity is refused as damaged).
  RadiosityState written = empty_state();
  IterationLog written_log;
  size_t at = 0;
  const auto next = [&]() {
    double v = 0;
    if (at + 8 <= size) std::memcpy(&v, data + at, 8);
    at += 8;
    return std::isfinite(v) ? v : 0.0;
  };
  for (double& v : written.phi) v = next();
  for (double& v : written.unshot) v = next();
  written.energy.emitted[0] = next();
  written_log.first_unshot = next();
  const size_t passes = at < size ? data[at] % 4 : 0;
  for (size_t p = 0; p < passes; ++p) written_log.passes.push_back({static_cast<int>(p), 7, 9, next(), next()});
  const auto path = fuzz::folder() / "roundtrip.bin";
  write_checkpoint(path, kKey, written, written_log);
  RadiosityState back = empty_state();
  IterationLog back_log;
  read_checkpoint(path, kKey, back, back_log);
  if (back.phi != written.phi || back.unshot != written.unshot || back.energy.emitted != written.energy.emitted ||
      back_log.passes.size() != written_log.passes.size() || back_log.first_unshot != written_log.first_unshot)
    __builtin_trap();
  return 0;
}
