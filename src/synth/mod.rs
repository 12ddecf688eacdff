//! Procedural furniture and scenes with known affordances, for tests and labelled data.
