"""Speech engines behind one interface: audio plus timed phoneme, word and mark events."""
