"""MPEG-4 face and body animation tables as CSV data (shipped as mpeg4fa.spec_data)."""
