"""Experiments that compare methods: ``fhslam bench`` (:mod:`fhslam.experiments.bench`:
speed and detection scores of every line extractor, SLAM steps per second), the SLAM
sweeps of notebook 07 (:mod:`fhslam.experiments.compare`) and the robustness of SLAM on a
real log degraded with many seeds (:mod:`fhslam.experiments.robustness`, ``fhslam sweep
--log``)."""
