"""meshcorr.shapes."""
