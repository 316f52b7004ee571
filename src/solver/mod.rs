//! Robot-agnostic prioritized task-stack solver (Poubel et al. eq. 2–8, Baerlocher & Boulic 2004).
