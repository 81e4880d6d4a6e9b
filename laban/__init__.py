"""Laban effort: kinematic features, feature selection, Naive Bayes and HMM classifiers, training data."""
