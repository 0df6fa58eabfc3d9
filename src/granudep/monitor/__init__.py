"""Stage package: monitor."""
