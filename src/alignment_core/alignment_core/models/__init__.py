"""Error-state models for transfer alignment (state labels, F, G, H, Q, R)."""
