scripts/maps-shipped-leaf.sh 1 45 --play-space all
