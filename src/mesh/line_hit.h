// A crossing of a line with a patch: what the tracer reports and what the tie
// order, the store and the transport work on.
#pragma once

namespace mpath {

struct LineHit {
  double t;
  int patch;
  bool along;       // the patch's front faces along the line's direction
  int traced = -1;  // index among a subset tracer's patches (-1: a tracer of every patch)
};

}  // namespace mpath
