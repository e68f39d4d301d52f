"""Experiments that compare methods: ``fhslam bench`` (:mod:`fhslam.experiments.bench`:
speed and detection scores of every line extractor, SLAM steps per second) and the SLAM
sweeps of notebook 07 (:mod:`fhslam.experiments.compare`)."""
