"""meshcorr.choice."""
