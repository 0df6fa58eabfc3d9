"""Stage package: da."""
