// A strategy's name resolved into the kernels' technique switches (kernels/params.h): which
// light-sampling technique a vertex uses at a path's first vertex and below it, whether light
// and BSDF samples are combined by MIS, whether paths continue, and whether the last vertex's
// BSDF sample is thinned. The kernels test switches, never a strategy.
#pragma once
#include "kernels/params.h"
#include "load/render_settings.h"

namespace et {

// Sets p's technique switches for `strategy`; leaves every other field as it is.
void set_technique(etk::EtkParams& p, Strategy strategy);

// Whether the sample_lights stage can draw the light samples of passes with p's switches
// (both techniques allow batches).
bool technique_batches_light_samples(const etk::EtkParams& p);

// Whether the pass sums a directional light set at every hit (the shade_lights stage).
bool technique_uses_light_set(const etk::EtkParams& p);

} // namespace et
