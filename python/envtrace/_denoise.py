"""envtrace.denoise: Open Image Denoise 2 through the library's denoiser, as render --denoise
uses it (host/lib/image/denoise.h), loaded at run time from what tools/setup installs."""

from . import _envtrace


def denoise(color, albedo=None, normal=None, hdr=True, prefilter=True):
    """The denoised H x W x 3 float32 image of `color` (linear radiance where hdr), guided by the
    first hit's albedo and normal (a Renderer's aovs()["albedo"], ["normal"]), which are denoised
    first where `prefilter` (OIDN's advice for a path tracer's guides). A normal needs an albedo.
    Raises envtrace.Error, saying how to install it, where Open Image Denoise is missing."""
    return _envtrace.denoise(color, albedo, normal, hdr, prefilter)
