"""The HTML report: numbers gathered from the public APIs, sections rendered from plain data."""
