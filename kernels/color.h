// Colour helpers shared by the kernels and the host.
#ifndef ETK_COLOR_H
#define ETK_COLOR_H
#include "compat.h"

ETK_BEGIN

// Rec. 709 luminance of linear RGB.
ETK_FN float etk_luma(float3 v) {
    return 0.2126f * v.x + 0.7152f * v.y + 0.0722f * v.z;
}

ETK_END

#endif
