"""python -m roughcontact.pipeline.config [FILE ...]: check the shipped config with FILEs added."""

from ..scenes import main

if __name__ == "__main__":
    main()
