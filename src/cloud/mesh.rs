//! Triangle-mesh readers (placeholder).
