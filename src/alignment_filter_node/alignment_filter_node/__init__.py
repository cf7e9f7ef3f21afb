"""Transfer-alignment filter: slave strapdown plus error-state Kalman filter."""
