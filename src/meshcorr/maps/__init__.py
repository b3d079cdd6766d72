"""meshcorr.maps."""
