"""Decoded streams written for other tools: glTF heads with their animation, and face-tracking formats."""
