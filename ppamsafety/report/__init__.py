"""Report assembly: the builder, the HTML page, the warm-up of the compiled kernels."""
