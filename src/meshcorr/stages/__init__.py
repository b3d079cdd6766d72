"""meshcorr.stages."""
