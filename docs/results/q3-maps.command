scripts/maps-table.sh 500000 2000000
