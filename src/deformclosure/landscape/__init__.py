"""The release landscape shared by every model: the one elastic-limit rule
(:mod:`.limit`)."""
