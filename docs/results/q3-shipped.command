scripts/maps-shipped.sh 1 45
