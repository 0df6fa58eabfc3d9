"""Stage package: regress."""
