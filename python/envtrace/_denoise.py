"""The place of envtrace.denoise: Open Image Denoise through the library's denoiser, wired here
once that library function is merged (denoise(color, albedo=None, normal=None) -> H x W x 3)."""

from . import _envtrace


def denoise(color, albedo=None, normal=None):
    """Not in this build yet: raises envtrace.Error."""
    raise _envtrace.Error("envtrace.denoise: this build has no denoiser yet (render --denoise "
                          "and the Python binding come with the denoiser's library function)")
