"""The conformance suite's data (manifest, vectors, faces), shipped as mpeg4fa.conformance_data."""
