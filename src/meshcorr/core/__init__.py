"""meshcorr.core."""
