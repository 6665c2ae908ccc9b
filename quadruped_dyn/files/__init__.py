"""Output files: directories proven writable before work starts."""
