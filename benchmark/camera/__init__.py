"""The depth camera: rendering, the sensor model, previews."""
