"""The randomised generalisation benchmark of the diagnosis (``python -m diagnosis.benchmark``).

Truth plants are hand-written state equations (:mod:`.plant`, ``plants_*``),
independent of the bond-graph code and of the diagnosis catalogue; concealed
effects (:mod:`.effects`) act on them at junctions, storage laws, inputs and
outputs; :mod:`.draw` draws random cases (plant x effect x place x magnitude x
excitation x noise), :mod:`.run` diagnoses each recording and scores the answer,
:mod:`.report` tabulates and plots the scores.
"""
