"""Standalone C from the CasADi graphs: emission, the verified build cache, the compiled
libraries loaded back into Python, and the C templates (``c/``)."""
