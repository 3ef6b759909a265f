"""Training the detector with plain PyTorch (the ``[train]`` extra) and exporting it to ONNX."""
