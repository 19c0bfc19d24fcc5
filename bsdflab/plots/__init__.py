"""matplotlib figures of bsdflab quantities (Agg backend; files, never windows)."""
