"""Shared test set-up: a backend with no screen."""

import matplotlib

matplotlib.use("Agg")
