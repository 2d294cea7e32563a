from ledsim.cli import console

console()
