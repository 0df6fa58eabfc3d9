"""Stage package: isph."""
