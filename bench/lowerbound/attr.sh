#!/bin/bash
# attr.sh ELF: text symbols with decimal sizes
avr-nm --size-sort -C -S "$1" | while read a s t n; do echo "$((16#$s)) $t $n"; done
