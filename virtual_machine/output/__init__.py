"""What a run leaves: motion files, report pages, Rerun recordings, texts, progress, the class verdict."""
