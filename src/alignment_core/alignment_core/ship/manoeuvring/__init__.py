"""Low-frequency manoeuvring: the MMG model, its autopilot and the course-keeping track."""


