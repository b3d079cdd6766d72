"""meshcorr.spectral."""
