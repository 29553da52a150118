"""Reports: a study's tables and figures as one self-contained HTML page and the same content as
Markdown (``document`` builds the content, ``render`` writes it)."""
