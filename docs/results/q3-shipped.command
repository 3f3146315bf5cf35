SHIPPED_RECODE=1 scripts/maps-shipped.sh 1 45
