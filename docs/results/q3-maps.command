scripts/maps-table.sh 250000 1000000
