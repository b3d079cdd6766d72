"""meshcorr.runtime."""
