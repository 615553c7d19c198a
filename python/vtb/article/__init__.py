"""The article's chain (Appl. Sci. 2025, 15, 8675): the TID problem, its sweep and
optimisation, designs judged over samples and speeds, the validation against references and
the reproduction of the article's figures and tables."""
