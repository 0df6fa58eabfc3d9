"""Stage package: figures."""
