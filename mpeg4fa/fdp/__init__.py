"""Face definition parameters (FDP): the data model and its file forms."""
